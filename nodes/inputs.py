"""A Geometry Nodes modifier's inputs by their names ("Alpha", "Iterations", ...), on every Blender.

Blender 4.x keeps the values as ID properties of the modifier: modifier["Socket_3"], a menu as its
item number, a field read from a vertex group through modifier["Socket_6_use_attribute"] and
modifier["Socket_6_attribute_name"]. Blender 5 keeps them as RNA under modifier.properties.inputs
(a menu as its item name, a field's source as ``type`` "VALUE" or "ATTRIBUTE"), and modifier[...]
raises TypeError there. The identifier of a name: ``input_identifier(modifier.node_group, name)``.
"""


def input_identifier(tree, name):
    for item in tree.interface.items_tree:
        if item.item_type == "SOCKET" and item.in_out == "INPUT" and item.name == name:
            return item.identifier
    raise KeyError(f"the node group '{tree.name}' has no input '{name}'")


def _rna_inputs(modifier):
    """Blender 5's modifier.properties.inputs, or None where the values are ID properties."""
    return getattr(getattr(modifier, "properties", None), "inputs", None)


def set_input(modifier, name, value):
    """Set an input's value; a menu (Method) takes its item's name or its position in the menu (0, 1, ...)."""
    tree = modifier.node_group
    identifier = input_identifier(tree, name)
    inputs = _rna_inputs(modifier)
    if _is_menu(tree, identifier):
        if inputs is not None and not isinstance(value, str):
            value = getattr(inputs, identifier).bl_rna.properties["value"].enum_items[value].identifier
        elif inputs is None and isinstance(value, str):
            # 4.x: the ID property's UI data lists the items as (name, name, description, icon, number).
            numbers = {entry[0]: entry[4] for entry in modifier.id_properties_ui(identifier).as_dict()["items"]}
            value = numbers[value]
    if inputs is not None:
        getattr(inputs, identifier).value = value
    else:
        modifier[identifier] = value
    modifier.id_data.update_tag()


def get_input(modifier, name):
    """An input's value as set_input takes it (a menu: its item's name on 5.x, its number on 4.x)."""
    identifier = input_identifier(modifier.node_group, name)
    inputs = _rna_inputs(modifier)
    return getattr(inputs, identifier).value if inputs is not None else modifier[identifier]


def set_input_attribute(modifier, name, attribute):
    """Read a field input ("Fixed Group") from a vertex group or attribute; "" goes back to its value."""
    identifier = input_identifier(modifier.node_group, name)
    inputs = _rna_inputs(modifier)
    if inputs is not None:
        item = getattr(inputs, identifier)
        item.type = "ATTRIBUTE" if attribute else "VALUE"
        item.attribute_name = attribute
    else:
        modifier[identifier + "_use_attribute"] = bool(attribute)
        modifier[identifier + "_attribute_name"] = attribute
    modifier.id_data.update_tag()


def get_input_attribute(modifier, name):
    """The vertex group or attribute a field input reads, "" when it uses its value."""
    identifier = input_identifier(modifier.node_group, name)
    inputs = _rna_inputs(modifier)
    if inputs is not None:
        item = getattr(inputs, identifier)
        return item.attribute_name if item.type == "ATTRIBUTE" else ""
    if modifier.get(identifier + "_use_attribute"):
        return modifier.get(identifier + "_attribute_name", "")
    return ""


def _is_menu(tree, identifier):
    return any(
        item.item_type == "SOCKET" and item.identifier == identifier and item.socket_type == "NodeSocketMenu"
        for item in tree.interface.items_tree
    )
