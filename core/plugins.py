"""The plugin manager factory. Nothing here runs at import time.

Built-in adapters and plugins are ordinary plugins, registered from one
tuple of module names (pytest's ``default_plugins``); third-party plugins come
from the ``ncperf`` entry-point group. ``NCPERF_DISABLE_PLUGINS`` (comma
separated names) keeps plugins out, built-in or not.
"""

from __future__ import annotations

import importlib
import os
import sys
from collections.abc import Iterable

import pluggy

from core import hookspecs
from core.model.errors import UsageError

#: The controller effects ncperf ships, one module each in ``plugins/effects/`` (the order
#: they are registered and fitted in): the one list of their names.
BUILTIN_EFFECTS: tuple[str, ...] = (
    "acceleration_ramps",
    "lookahead_depth",
    "block_cycle_time",
    "corner_tolerance",
    "normal_acceleration_factor",
    "arc_feed_limit",
    "axis_dynamics",
    "feed_override",
    "servo_lag",
    "jerk_filter",
    "path_compression",
    "last_block_acceleration",
    "arc_acceleration",
    "exact_stop",
    "path_feed_limit",
)

#: Built-in plugins, by module name; registered under that name.
BUILTIN_PLUGINS: tuple[str, ...] = (
    "adapters.gcode",
    "adapters.cl_data",
    "adapters.esprit_com",
    "adapters.svg",
    "adapters.html",
    "adapters.traces",
    "plugins.tangential",
    "plugins.curvature",
    "plugins.ncu_capacity",
    "plugins.exact_stop",
    "plugins.feed_limit",
    "plugins.rotary",
    *(f"plugins.effects.{name}" for name in BUILTIN_EFFECTS),
)

DISABLE_ENV = "NCPERF_DISABLE_PLUGINS"


def disabled_from_env() -> set[str]:
    """Plugin names listed in NCPERF_DISABLE_PLUGINS."""
    raw = os.environ.get(DISABLE_ENV, "")
    return {name.strip() for name in raw.split(",") if name.strip()}


#: The built-ins that add ``ncperf`` subcommands: all the command line's parser needs.
COMMAND_PLUGINS: tuple[str, ...] = ("adapters.esprit_com",)


def make_plugin_manager(
    *,
    builtins: Iterable[str] = BUILTIN_PLUGINS,
    entry_points: bool = True,
    disable: Iterable[str] = (),
    extra: Iterable[object] = (),
) -> pluggy.PluginManager:
    """A fresh plugin manager with the hookspecs and the plugins registered.

    Parameters
    ----------
    builtins : iterable of str
        Module names of the built-in plugins.
    entry_points : bool
        Load third-party plugins from the ``ncperf`` entry-point group.
    disable : iterable of str
        Plugin names to block, in addition to NCPERF_DISABLE_PLUGINS.
    extra : iterable of objects
        More plugins (modules or objects with hookimpls), e.g. from tests.
    """
    pm = pluggy.PluginManager(hookspecs.PROJECT)
    pm.add_hookspecs(hookspecs)
    for name in set(disable) | disabled_from_env():
        pm.set_blocked(name)
    if entry_points and _declares_group(hookspecs.PROJECT):
        pm.load_setuptools_entrypoints(hookspecs.PROJECT)
    _register(pm, builtins)
    for plugin in extra:
        pm.register(plugin)
    pm.check_pending()
    return pm


def _declares_group(group: str) -> bool:
    """Whether any installed distribution on ``sys.path`` may declare entry points of
    ``group``: a ``[group]`` section in one of the ``entry_points.txt`` files of the
    ``*.dist-info`` / ``*.egg-info`` folders (the PyPA entry-points specification).

    Only a shortcut: when it says yes, pluggy's loader (``importlib.metadata``) reads them
    properly; when no metadata declares the group there is nothing to load, and the 50-80 ms
    that importing ``importlib.metadata`` costs are saved (issue 13). A folder that cannot
    be listed or a path that is not a folder (zip files, eggs) sends it to the real loader.
    """
    for entry in sys.path:
        folder = entry or "."
        if not os.path.isdir(folder):
            if os.path.exists(folder):
                return True  # a zip or an egg: let importlib.metadata look inside
            continue
        try:
            names = os.listdir(folder)
        except OSError:
            return True
        for name in names:
            if not name.endswith((".dist-info", ".egg-info")):
                continue
            try:
                with open(os.path.join(folder, name, "entry_points.txt"), encoding="utf-8") as fh:
                    text = fh.read()
            except (FileNotFoundError, NotADirectoryError):
                continue  # no entry points (an egg-info file holds none)
            except (OSError, UnicodeDecodeError):
                return True
            for line in text.splitlines():
                line = line.strip()
                if line.startswith("[") and line.endswith("]") and line[1:-1].strip() == group:
                    return True
    return False


def _register(pm: pluggy.PluginManager, builtins: Iterable[str]) -> None:
    for modname in builtins:
        if pm.is_blocked(modname) or pm.has_plugin(modname):
            continue
        try:
            module = importlib.import_module(modname)
        except ImportError as exc:
            raise UsageError(f"cannot load built-in plugin {modname}: {exc}") from exc
        pm.register(module, name=modname)


def command_plugin_manager() -> pluggy.PluginManager:
    """The third-party plugins and the built-ins that add commands (:data:`COMMAND_PLUGINS`):
    what the command line's parser needs, without importing the other built-ins."""
    return make_plugin_manager(builtins=COMMAND_PLUGINS)


def complete_plugin_manager(pm: pluggy.PluginManager) -> pluggy.PluginManager:
    """``pm`` from :func:`command_plugin_manager` with every built-in registered, in the
    order :func:`make_plugin_manager` gives (its hooks then run in the same order)."""
    for modname in COMMAND_PLUGINS:
        plugin = pm.get_plugin(modname)
        if plugin is not None:
            pm.unregister(plugin, name=modname)
    _register(pm, BUILTIN_PLUGINS)
    pm.check_pending()
    return pm
