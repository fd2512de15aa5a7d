"""What every smoothing route checks, reads and writes of a Blender object, whatever it smooths.

Shared by the mesh jobs, the point-cloud clouds and the command line: editable data, each datablock
once, the positions of the active shape key (or of the data), finite coordinates, and the write-back
that keeps relative shape keys in step.
"""

from .. import core
from ..jobs import InputError
from . import mesh_io


def check_editable(obj):
    for what, datablock in (("Object", obj), ("Data", obj.data)):
        if datablock.library is not None:
            raise InputError(
                f"{what} '{datablock.name}' is linked from library '{datablock.library.filepath}' "
                "and cannot be edited: make it local first (Object > Relations > Make Local)"
            )
        if not datablock.is_editable:
            raise InputError(f"{what} '{datablock.name}' cannot be edited (a library override?): make it local first")


def unique_data(objects, first=None):
    """``objects`` with each object data once (a mesh shared by several objects is smoothed once),
    read through ``first`` when it is among them."""
    ordered = sorted(objects, key=lambda obj: obj != first)
    seen, unique = set(), []
    for obj in ordered:
        if obj.data.as_pointer() not in seen:
            seen.add(obj.data.as_pointer())
            unique.append(obj)
    return unique


def active_key(obj):
    """The shape key that holds what the user sees and edits, or None for data without keys."""
    keys = getattr(obj.data, "shape_keys", None)
    return obj.active_shape_key if keys is not None else None


def read_positions(obj, noun=("vertex", "vertices")):
    """(positions, key_block): the active shape key's or the data's positions, checked to be finite.
    ``noun``: what the message calls one and several of them."""
    key_block = active_key(obj)
    positions = mesh_io.read_shape_key(key_block) if key_block is not None else mesh_io.read_positions(obj.data)
    bad = core.nonfinite_rows(positions)
    if bad.size:
        raise InputError(
            f"Object '{obj.name}' has {bad.size} {noun[bad.size != 1]} with NaN or infinite coordinates "
            f"(first: {noun[0]} {int(bad[0])}): fix or delete them first"
        )
    return positions, key_block


def world_frame(obj):
    """The stretch that takes ``obj``'s coordinates to its world-space shape (core.world_frame), None where its
    transform keeps lengths; InputError for a transform that flattens it."""
    try:
        return core.world_frame(obj.matrix_world)
    except ValueError as error:
        raise InputError(f"Object '{obj.name}': {error}") from None


def write_positions(obj, key_block, before, result):
    """Write ``result`` where ``before`` was read. Keys relative to a smoothed key (directly or through
    a chain) move by the same displacement, as Blender's own tools do; the mesh follows its basis."""
    data = obj.data
    if key_block is None:
        mesh_io.write_positions(data, result)
        return
    keys = data.shape_keys
    dependent = dependent_keys(keys, key_block) if keys.use_relative else []
    if dependent:
        displacement = result - before
        for key in dependent:
            mesh_io.write_shape_key(key, mesh_io.read_shape_key(key) + displacement)
    mesh_io.write_shape_key(key_block, result)
    if key_block == keys.reference_key:
        mesh_io.write_positions(data, result)
    else:
        data.update()  # the basis (and so the mesh positions) stay as they were


def dependent_keys(keys, key_block):
    """The shape keys whose chain of relative keys leads to ``key_block`` (not the key itself)."""
    blocks = list(keys.key_blocks)
    depends = {key_block.name}
    grew = True
    while grew:  # breadth-first over the relative keys; a cycle cannot loop
        grew = False
        for block in blocks:
            if block.name not in depends and block.relative_key.name in depends:
                depends.add(block.name)
                grew = True
    return [block for block in blocks if block.name in depends and block != key_block]
