"""Golden-frame testing for projects that render motion: :mod:`~motion2video.testing.golden` (``assert_frames_match``,
the metrics, the synthetic test motions); the pytest fixture ``golden_frames`` is :mod:`motion2video.pytest_plugin`."""
