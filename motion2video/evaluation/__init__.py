"""Evaluation protocols, one place: held-out forecasting metrics (:mod:`~motion2video.evaluation.forecasting`,
the DLow protocol of ``evaluate`` and Table 1 of ``results.md``), behaviour transfer's Table 1 / Table 3
(:mod:`~motion2video.evaluation.transfer_protocol`), the known-answer analogy
(:mod:`~motion2video.evaluation.analogy_benchmark`) and the frame generators' scores
(:mod:`~motion2video.evaluation.frame_generators`); the metric functions (:mod:`~motion2video.evaluation.metrics`), the ADE plot (:mod:`~motion2video.evaluation.plots`)
and the benchmark scripts' shared timing (:mod:`~motion2video.evaluation.benchtools`).
"""
