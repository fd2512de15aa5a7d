"""The smoothing jobs every route shares, without Blender: from settings to core's options, the core run,
the report's words.

``mesh`` holds one job per mesh (the mesh operators' and the command line's), ``points`` one cloud per
point cloud (the point operator's and the command line's --points). Nothing here imports bpy: the
operators (operators/) read Blender objects into jobs and write their results back, the command line
(cli/) reads scan files into them and writes the result files, in any Python with NumPy and SciPy.
"""


class InputError(Exception):
    """A message for the user about an object, a file's mesh or the settings; nothing has been written."""
