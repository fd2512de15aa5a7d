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


def set_by_caller(props, names):
    """The names among ``names`` that the caller of an operator set (a script's arguments, a button's, an edit
    in the redo panel): what the Automatic Amount's rule reads as given (settings_spec.automatic). Values
    Blender brings back from an operator's last run ("ghost" values) are not: is_property_set leaves them out.
    A snapshot without Blender's properties (settings_spec.MeshSettings) has none."""
    properties = getattr(props, "properties", None)
    if properties is None:
        return frozenset()
    declared = properties.bl_rna.properties
    return frozenset(name for name in names if name in declared and properties.is_property_set(name))


def annotations(settings):
    """{identifier: property} for a class body's ``__annotations__`` (Blender registers those)."""
    return {setting.name: bpy_property(setting) for setting in settings}
