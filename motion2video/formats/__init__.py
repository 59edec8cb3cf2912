"""Files in and out: one module per motion format, each reading into the project's containers, and video.

- :mod:`~motion2video.formats.bvh`: BVH motion capture (reader, forward kinematics, canonical conversion)
- :mod:`~motion2video.formats.bvh_write`: canonical joints -> BVH (``--bvh DIR``; rig ``motion2video-h36m``)
- :mod:`~motion2video.formats.deepmimic`: DeepMimic motion files (character found beside, in the DeepMimic
  repository layout, or the shipped ``data/humanoid3d.txt``)
- :mod:`~motion2video.formats.joint_arrays`: ``.npy`` / one-array ``.npz`` joint arrays (SMPL-22, H36M-17, K futures)
- :mod:`~motion2video.formats.manifest`: the mocap / face ``manifest.csv`` (true fps, labels)
- :mod:`~motion2video.formats.npz`: Motion / FaceMotion ``.npz`` (atomic writes, no pickles)
- :mod:`~motion2video.formats.openpose`: OpenPose JSON folders -> 2D canonical Motion
- :mod:`~motion2video.formats.videopose3d`: VideoPose3D ``data_3d_h36m.npz`` -> canonical Motions
- :mod:`~motion2video.formats.face_csv`: Live Link Face ARKit CSV -> FaceMotion
- :mod:`~motion2video.formats.resample`: linear frame-rate conversion

:mod:`motion2video.formats.io` dispatches on the path (``load_motion``, ``save_motion``).
:mod:`motion2video.formats.video` writes mp4 / GIF (atomic, streaming), grids, borders and labels.
"""
