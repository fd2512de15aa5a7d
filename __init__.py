"""HC Smooth: noise removal for scans without the shrinkage of Laplacian smoothing.

Blender loads this package as an extension (``bl_ext.<repo>.hc_smooth``). Registration only:
the operators live in ``operators/``, the panel, menus and settings in ``ui/``, the
`blender -c hc_smooth` command in ``cli/``, the modifier's Geometry Nodes group in ``nodes/``, the
mathematics in ``core/`` (which never imports bpy). ``settings_spec.py`` (every setting, declared
once) and the command line's parsing (``cli/arguments.py``) import without Blender.
"""

from . import cli, operators, ui


def register():
    operators.register()
    ui.register()
    cli.register()


def unregister():
    cli.unregister()
    ui.unregister()
    operators.unregister()
