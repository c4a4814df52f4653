"""Scripts that run inside Blender (the binary's ``--python``, or a Python that has ``bpy``), not in choreo."""
