"""Geometry Nodes the add-on builds: the "HC Smooth" group behind the HC Smooth modifier.

A Blender-side adapter like operators/: the paper's step in nodes, tested against core. Imported
only inside Blender (it uses bpy); core/ stays free of it.
"""
