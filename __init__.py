"""HC Smooth: noise removal for scans without the shrinkage of Laplacian smoothing.

Blender loads this package as an extension (``bl_ext.<repo>.hc_smooth``). Registration only:
the operators live in ``operators/``, the panel, menus and settings in ``ui/``, the
`blender -c hc_smooth` command in ``cli/``, the modifier's Geometry Nodes group in ``nodes/``, the
mathematics in ``core/`` (which never imports bpy). ``settings_spec.py`` (every setting, declared
once) and the command line's parsing (``cli/arguments.py``) import without Blender.
"""

try:
    import scipy  # noqa: F401  (the operators need it; Blender does not bundle it)
except ModuleNotFoundError:
    raise ImportError(  # name: Blender then says "Add-on not loaded: <name>, cause: <this message>"
        "HC Smooth needs SciPy, which this Blender cannot import. Install the HC Smooth zip built for "
        "your platform (it carries SciPy: `make dist`), or install SciPy into this Python "
        "(python -m pip install scipy)",
        name=__name__,
    ) from None

import bpy  # noqa: E402

from . import cli, operators  # noqa: E402
from .ui import fixed, panel, preset, settings  # noqa: E402

# The modules of ui/ that register, in order. ui/__init__ imports none of them; they import operators/ (its
# draw.py draws the settings in every panel), which imports nothing from ui/.
UI = (settings, preset, fixed, panel)


def register():
    operators.register()
    for module in UI:
        for cls in module.classes:
            bpy.utils.register_class(cls)
        module.register()
    cli.register()


def unregister():
    cli.unregister()
    for module in reversed(UI):
        module.unregister()
        for cls in reversed(module.classes):
            bpy.utils.unregister_class(cls)
    operators.unregister()
