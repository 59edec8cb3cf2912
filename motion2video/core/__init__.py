"""The pure core: motion containers, skeletons, errors, atomic writes, the camera, rotations
and the learning-rate schedule.

Only numpy (and the standard library) below this line: nothing here imports the rest of motion2video, the
renderers or torch, so every other layer may import it.
"""
