"""Output files, written one way: atomically, never over anything but a regular file, never over
an input, and all or none of a run's outputs.

- :func:`check_outputs` runs before any work: each output must be a new name or an existing
  *regular* file (not a folder, a symbolic link, a device node, a FIFO or a socket: replacing
  those would replace the link or the node itself, as root even ``/dev/null``), in an existing
  folder, distinct from every input and from the other outputs.
- :func:`atomic_writer` writes into a temporary file beside the target. Inside a
  :func:`transaction` (the CLI opens one per command) the temporary files replace their targets
  only when the whole command has succeeded; a failure anywhere removes every one of them, so
  a run that fails leaves no output of its own behind (not even the SVG it wrote before the
  JSON failed) and every file it would have replaced untouched.
- A failed write (disk full, quota, I/O error) is an :class:`OutputError` naming the file.
"""

from __future__ import annotations

import contextlib
import contextvars
import os
import stat
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import IO, Any

from core.model.errors import NcperfError, UsageError
from core.model.inputs import file_kind


class OutputError(NcperfError):
    """An output file cannot be written (disk full, permissions, I/O error)."""


#: The pending (temporary file, target) pairs of the open transaction, if any.
_PENDING: contextvars.ContextVar[list[tuple[str, Path]] | None] = contextvars.ContextVar(
    "ncperf_pending_outputs", default=None
)


def check_target(path: str | os.PathLike[str]) -> None:
    """Raise :class:`UsageError` unless ``path`` may be written: a new name, or a regular file
    (not followed through a symbolic link), in an existing folder."""
    target = Path(path)
    try:
        st = os.lstat(target)
    except FileNotFoundError:
        st = None
    except OSError as exc:
        raise UsageError(f"{target}: cannot write: {exc.strerror}") from None
    if st is not None and not stat.S_ISREG(st.st_mode):
        raise UsageError(
            f"{target}: is {file_kind(st.st_mode)}; ncperf only replaces regular files"
        )
    folder = target.parent
    if not folder.is_dir():
        raise UsageError(f"{target}: folder {folder} does not exist")


def _same(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:
        return os.path.abspath(a) == os.path.abspath(b)


def check_outputs(
    outputs: Iterable[str | os.PathLike[str] | None],
    inputs: Iterable[str | os.PathLike[str] | None] = (),
) -> None:
    """Check every output before any work (see the module docstring)."""
    outs = [Path(o) for o in outputs if o is not None]
    ins = [Path(i) for i in inputs if i is not None]
    for k, out in enumerate(outs):
        check_target(out)
        for i in ins:
            if _same(out, i):
                raise UsageError(f"{out}: is an input of this run; it would be overwritten")
        for other in outs[:k]:
            if _same(out, other):
                raise UsageError(f"{out}: named for two outputs")


@contextlib.contextmanager
def transaction() -> Iterator[None]:
    """All outputs written inside replace their targets at the end, or none does."""
    pending: list[tuple[str, Path]] = []
    token = _PENDING.set(pending)
    try:
        yield
    except BaseException:
        for tmp, _ in pending:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
        raise
    finally:
        _PENDING.reset(token)
    _commit(pending)


def _commit(pending: list[tuple[str, Path]]) -> None:
    for k, (tmp, target) in enumerate(pending):
        try:
            check_target(target)  # still a regular file or absent: nothing swapped in since
            os.replace(tmp, target)
        except (OSError, UsageError) as exc:
            for rest, _ in pending[k:]:
                with contextlib.suppress(OSError):
                    os.unlink(rest)
            if isinstance(exc, UsageError):
                raise
            raise OutputError(f"cannot write: {exc.strerror}", source=str(target)) from None


@contextlib.contextmanager
def atomic_writer(path: str | os.PathLike[str], *, binary: bool = False) -> Iterator[IO]:
    """Open a temporary file beside ``path``; it replaces ``path`` only if the block succeeds
    (and, inside a :func:`transaction`, only when the transaction does).

    Raises :class:`UsageError` when ``path`` may not be replaced and :class:`OutputError`
    naming the file when it cannot be written.
    """
    target = Path(path)
    check_target(target)
    folder = target.parent if str(target.parent) else Path(".")
    import tempfile  # here, not at import: ncperf --help does not pay for it

    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".part", dir=folder)
    except OSError as exc:
        raise OutputError(f"cannot write: {exc.strerror}", source=str(target)) from None
    try:
        fh: IO[Any] = (
            os.fdopen(fd, "wb") if binary else os.fdopen(fd, "w", encoding="utf-8", newline="\n")
        )
        try:
            with fh:
                yield fh
            os.chmod(tmp, 0o644)
        except OSError as exc:
            raise OutputError(f"cannot write: {exc.strerror}", source=str(target)) from None
        pending = _PENDING.get()
        if pending is None:
            _commit([(tmp, target)])  # outside a transaction: replace at once
        else:
            pending.append((tmp, target))
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
