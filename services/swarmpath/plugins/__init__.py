"""Plugins: optimizers, functions, suites and planners that live outside swarmpath.

The extension points themselves are the registries' (``swarmpath.optimizers.register``,
``swarmpath.functions.register_function`` / ``register_suite``,
``swarmpath.planners.register_planner``); this package finds and loads the code that uses them
(:mod:`.loading`: entry points, ``--plugin``, ``SWARMPATH_PLUGINS``) and says where each name
comes from (:mod:`.origin`). See docs/extending.md.
"""

from swarmpath.plugins.loading import (
    ENV,
    GROUPS,
    PluginError,
    export,
    load_all,
    load_plugin,
    load_plugins,
    problems,
)
from swarmpath.plugins.origin import Origin
from swarmpath.registry import ExtensionClash

__all__ = [
    "ENV",
    "GROUPS",
    "ExtensionClash",
    "Origin",
    "PluginError",
    "export",
    "load_all",
    "load_plugin",
    "load_plugins",
    "problems",
]
