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

from . import cli, operators, ui  # noqa: E402


def register():
    operators.register()
    ui.register()
    cli.register()


def unregister():
    cli.unregister()
    ui.unregister()
    operators.unregister()
