"""Writing arms to files: URDF (armdyn.io.urdf_out) and armdyn's own JSON model file (armdyn.io.model_file)."""
