"""Blender's side of settings_spec: the properties built from the declarations.

The operators and the scene settings (ui/settings.py) take their ``__annotations__`` from
``annotations()``, so both are the same declaration turned into bpy.props. How panels draw them is
operators/draw.py.
"""

from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty

PROPERTY = {
    "enum": EnumProperty,
    "float": FloatProperty,
    "int": IntProperty,
    "bool": BoolProperty,
    "string": StringProperty,
}
LIMITS = ("min", "max", "soft_max", "step", "precision", "subtype")


def bpy_property(setting):
    """A settings_spec.Setting as a bpy.props property."""
    options = {"name": setting.label, "description": setting.description, "default": setting.default}
    options.update((key, getattr(setting, key)) for key in LIMITS if getattr(setting, key) is not None)
    if setting.kind == "enum":
        options["items"] = [(choice.identifier, choice.label, choice.description) for choice in setting.items]
    return PROPERTY[setting.kind](**options)


def annotations(settings):
    """{identifier: property} for a class body's ``__annotations__`` (Blender registers those)."""
    return {setting.name: bpy_property(setting) for setting in settings}
