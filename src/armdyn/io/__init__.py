"""Writing arms to files: URDF (armdyn.io.urdf_out), MuJoCo MJCF (armdyn.io.mjcf_out) and armdyn's own JSON
model file (armdyn.io.model_file)."""
