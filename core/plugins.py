"""The plugin manager factory. Nothing here runs at import time.

Built-in adapters and plugins are ordinary plugins, registered from one
tuple of module names (pytest's ``default_plugins``); third-party plugins come
from the ``ncperf`` entry-point group. ``NCPERF_DISABLE_PLUGINS`` (comma
separated names) keeps plugins out, built-in or not.
"""

from __future__ import annotations

import importlib
import os
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
    if entry_points:
        pm.load_setuptools_entrypoints(hookspecs.PROJECT)
    for modname in builtins:
        if pm.is_blocked(modname) or pm.has_plugin(modname):
            continue
        try:
            module = importlib.import_module(modname)
        except ImportError as exc:
            raise UsageError(f"cannot load built-in plugin {modname}: {exc}") from exc
        pm.register(module, name=modname)
    for plugin in extra:
        pm.register(plugin)
    pm.check_pending()
    return pm
