"""pythonnet, imported only here and only when called: the .NET runtime, the emulation
assembly, attaching to a running ESPRIT, and COM late binding.

``import adapters.esprit_com`` never imports this module's dependencies: ``clr`` comes in
the first time a caller asks for the emulation or for a live ESPRIT.
"""

from __future__ import annotations

import functools
import os
import platform
import sys
import warnings
from pathlib import Path
from types import ModuleType

from adapters.esprit_com.object_model import INDEXER, METHODS, PROG_ID, ComObject
from core.model.errors import UsageError

#: Where ``scripts/setup_esprit_emulation.sh`` writes the emulation; this variable overrides it
#: (e.g. for an installed, non-editable ncperf).
DLL_ENV = "NCPERF_ESPRIT_EMULATION_DLL"
DEFAULT_DLL = Path(__file__).resolve().parent / "build" / "EspritEmulation.dll"
SETUP = "scripts/setup_esprit_emulation.sh"

#: clr_loader warns on every load with Debian's Mono 6.8; pythonnet works on it here.
MONO_WARNING = r"Hosting Mono versions before v6\.12"


class DotnetUnavailable(UsageError):
    """pythonnet, a .NET runtime or the emulation assembly is missing; ``reason`` says which."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason


def emulation_dll() -> Path:
    """Path of the compiled emulation assembly (it may not exist)."""
    return Path(os.environ.get(DLL_ENV) or DEFAULT_DLL)


@functools.cache
def load_runtime() -> str:
    """Load pythonnet's .NET runtime once per process; returns its kind ("mono" or "netfx").

    Mono needs ``MONO_THREADS_SUSPEND=preemptive`` before it starts, or two threads calling
    .NET deadlock (pytest's and the finaliser's, for one); a value the user set is kept.
    """
    try:
        import pythonnet
    except ImportError:
        raise DotnetUnavailable(
            "pythonnet is not installed (pip install 'ncperf[esprit]')"
        ) from None
    kind = "netfx" if sys.platform == "win32" else "mono"
    if kind == "mono":
        os.environ.setdefault("MONO_THREADS_SUSPEND", "preemptive")
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=MONO_WARNING, category=UserWarning)
        try:
            pythonnet.load(kind)
        except Exception as exc:  # clr_loader raises RuntimeError with the cause chained
            cause = exc.__cause__ or exc
            hint = f"; {SETUP} installs Mono" if kind == "mono" else ""
            raise DotnetUnavailable(
                f"the .NET runtime ({kind}) could not be loaded: {exception_text(cause)}{hint}"
            ) from exc
    return kind


@functools.cache
def load_emulation() -> ModuleType:
    """The emulation's .NET namespace ``EspritEmulation``, its assembly loaded once."""
    dll = emulation_dll()
    if not dll.is_file():
        raise DotnetUnavailable(f"the .NET ESPRIT emulation is not built ({dll}): run {SETUP}")
    load_runtime()
    import clr

    clr.AddReference(str(dll))
    # A .NET namespace: importable only once clr has loaded the assembly, so no stubs.
    import EspritEmulation  # type: ignore[import-not-found]

    return EspritEmulation


def attach_running_esprit() -> LateBound:
    """The running ESPRIT's Application object, reached through COM.

    Raises :class:`~core.model.errors.UsageError` saying why ESPRIT could not be reached (not
    Windows, no pythonnet, no running ESPRIT).
    """
    why = "ESPRIT could not be reached"
    if sys.platform != "win32":
        raise UsageError(
            f"{why}: ESPRIT runs on Windows and this is {platform.system()} "
            "(--emulate PROGRAM runs the same flow on the headless emulation)"
        )
    try:
        load_runtime()
    except DotnetUnavailable as exc:
        raise UsageError(f"{why}: {exc.reason}") from None
    # Marshal.GetActiveObject is .NET Framework's way into the running object table;
    # pythonnet hosts .NET Framework on Windows by default.
    from System.Runtime.InteropServices import Marshal

    try:
        app = Marshal.GetActiveObject(PROG_ID)
    except Exception as exc:
        raise UsageError(
            f"{why}: no running ESPRIT is registered as {PROG_ID} ({exception_text(exc)}); "
            "start ESPRIT and open the document first"
        ) from None
    return LateBound(app)


def as_host(obj: ComObject) -> ComObject:
    """``obj`` wrapped in :class:`LateBound` if it is a COM object (what the add-in shim
    passes), else unchanged (the emulation, the Python twin)."""
    if "clr" not in sys.modules or isinstance(obj, LateBound):
        return obj
    import System
    from System.Runtime.InteropServices import Marshal

    if isinstance(obj, System.Object) and Marshal.IsComObject(obj):
        return LateBound(obj)
    return obj


def exception_text(exc: BaseException) -> str:
    """One line for a Python or .NET exception (.NET's str() carries the stack trace)."""
    inner = getattr(exc, "InnerException", None)
    if inner is not None:
        return exception_text(inner)
    text = getattr(exc, "Message", None) or str(exc) or type(exc).__name__
    return " ".join(str(text).split())


class LateBound:
    """A .NET or COM object whose members are reached by name at run time.

    ESPRIT's COM objects reach Python as ``System.__ComObject``, whose members pythonnet
    cannot see without ESPRIT's interop assemblies; ``Type.InvokeMember`` goes through
    ``IDispatch`` instead, exactly as VBA does. Members in ``object_model.METHODS`` are
    called, every other name is a property; ``obj[i]`` is the default ``Item`` member.
    On plain .NET objects (the emulation) the same calls go through reflection, which is
    how the tests exercise this path.
    """

    __slots__ = ("_target",)
    _target: ComObject

    def __init__(self, target: ComObject) -> None:
        object.__setattr__(self, "_target", target)

    def __getattr__(self, name: str) -> object:
        if name.startswith("_"):
            raise AttributeError(name)
        if name in METHODS:
            return functools.partial(self._invoke, name, "method")
        return self._invoke(name, "get")

    def __setattr__(self, name: str, value: object) -> None:
        self._invoke(name, "set", value)

    def __getitem__(self, index: int) -> object:
        return self._invoke(INDEXER, "get", index)

    def __eq__(self, other: object) -> bool:
        other = other._target if isinstance(other, LateBound) else other
        return bool(self._target.Equals(other))

    def __hash__(self) -> int:
        return int(self._target.GetHashCode())

    def __repr__(self) -> str:
        return f"LateBound({self._target.GetType().FullName})"

    def _invoke(self, name: str, how: str, *args: object) -> object:
        import System
        from System.Reflection import BindingFlags
        from System.Runtime.InteropServices import Marshal

        target = self._target
        flags = {
            "get": BindingFlags.GetProperty,
            "set": BindingFlags.SetProperty,
            "method": BindingFlags.InvokeMethod,
        }[how]
        flags |= BindingFlags.Public | BindingFlags.Instance
        values = [_to_net(a) for a in args]
        if how == "set" and not Marshal.IsComObject(target):
            # Reflection does not narrow Int32 to UInt32 (ActiveColor) as IDispatch does.
            prop = target.GetType().GetProperty(name)
            if prop is not None and prop.PropertyType.IsPrimitive:
                values = [getattr(System, prop.PropertyType.Name)(args[0])]
        try:
            result = target.GetType().InvokeMember(
                name, flags, None, target, System.Array[System.Object](values)
            )
        except (System.MissingMemberException, System.MissingMethodException):
            raise AttributeError(f"{target.GetType().FullName} has no member {name}") from None
        except System.Runtime.InteropServices.COMException as exc:
            if (exc.HResult & 0xFFFFFFFF) == 0x80020006:  # DISP_E_UNKNOWNNAME
                raise AttributeError(f"COM object has no member {name}") from None
            raise
        except System.Reflection.TargetInvocationException as exc:
            inner = exc.InnerException
            raise (inner if isinstance(inner, BaseException) else exc) from None
        return _from_net(result)


def _to_net(value: object) -> object:
    import System

    if isinstance(value, LateBound):
        return value._target
    if isinstance(value, bool):
        return System.Boolean(value)
    if isinstance(value, int):
        # Python ints box as Int64, which neither reflection nor most IDispatch servers
        # take for an int or uint parameter.
        if -(2**31) <= value < 2**31:
            return System.Int32(value)
        if 0 <= value < 2**32:
            return System.UInt32(value)
        return System.Int64(value)
    if isinstance(value, float):
        return System.Double(value)
    return value


def _from_net(value: object) -> object:
    import System

    if value is None or isinstance(value, bool | int | float | str):
        return value
    if isinstance(value, System.Enum):
        return int(value)
    return LateBound(value)
