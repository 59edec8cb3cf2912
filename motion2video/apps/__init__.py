"""The applications, siblings: each composes the stages (:mod:`motion2video.stages`); none imports another.

- :mod:`~motion2video.apps.sample`: K sampled futures of a clip as a grid video (``motion2video sample``);
- :mod:`~motion2video.apps.synthesize`: futures -> structures -> generated frames (``synthesize``, ``make demo``);
- :mod:`~motion2video.apps.transfer`: behaviour transfer and flow samples (``transfer``);
- :mod:`~motion2video.apps.analogy`: MT-VAE analogy A : B :: C : D (``analogy``).
"""
