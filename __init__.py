"""HC Smooth: noise removal for scans without the shrinkage of Laplacian smoothing.

Blender loads this package as an extension (``bl_ext.<repo>.hc_smooth``). Registration only:
the operators live in ``operators/``, the panel, menus and settings in ``ui/``, the
`blender -c hc_smooth` command in ``cli/``, the mathematics
in ``core/`` (which never imports bpy).
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
