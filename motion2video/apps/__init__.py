"""The applications, siblings: each composes the stages (:mod:`motion2video.stages`); none imports another.

- :mod:`~motion2video.apps.sample`: K sampled futures of a clip as a grid video (``motion2video sample``);
- :mod:`~motion2video.apps.synthesize`: futures -> structures -> generated frames (``synthesize``, ``make demo``);
- :mod:`~motion2video.apps.transfer`: behaviour transfer and flow samples (``transfer``);
- :mod:`~motion2video.apps.analogy`: MT-VAE analogy A : B :: C : D (``analogy``);
- :mod:`~motion2video.apps.render`: a motion file as a structure video (``render``).

Beside them, not siblings: :mod:`~motion2video.apps.batch` (``batch``: runs command lines, ``render`` in-process;
:mod:`~motion2video.apps.gallery` is its HTML page) and :mod:`~motion2video.apps.doctor` (``doctor``'s checks).
"""
