"""Per-action and macro-averaged metrics: one pooled average over windows is dominated by the action
with the most windows (salsa, Indian dance) and can hide a regression on the others.

Pure functions on per-window metric arrays: :func:`group_by_action` gives each action's window indices (the
action is the window's clip label, :func:`motion2video.data.corpus.action_class` of the manifest's action
column), :func:`per_action_means` averages per-window metrics within each action, :func:`macro_average` is the
unweighted mean over actions and :func:`window_weighted_average` the mean weighted by window counts (which
equals the pooled mean over all windows for any per-window metric); :func:`ratios_to` divides a model's per-action
ADE and FDE by a baseline's (zero-velocity, in docs/results.md's tables).
"""

from __future__ import annotations

import numpy as np

UNLABELLED = "unlabelled"  # the action of windows whose clip has no label
COUNT_KEY = "windows"  # the per-action entry holding the number of windows


def action_names(labels) -> np.ndarray:
    """(N,) str: each window's action label, :data:`UNLABELLED` for None or empty labels."""
    return np.array([str(lab) if lab else UNLABELLED for lab in labels], dtype=object)


def group_by_action(labels) -> dict[str, np.ndarray]:
    """Window indices per action: ``{action: (n_a,) int64}``, the actions ordered by window count (largest
    first), then by name. ``labels``: (N,) per-window action labels (None = unlabelled)."""
    names = action_names(labels)
    actions = sorted(set(names.tolist()), key=lambda a: (-int((names == a).sum()), a))
    return {a: np.flatnonzero(names == a) for a in actions}


def per_action_means(per_window: dict[str, np.ndarray], groups: dict[str, np.ndarray]) -> dict[str, dict[str, float]]:
    """Mean of every per-window metric within each action, plus the action's window count.

    Args:
        per_window: metric name -> (N,) value per window.
        groups: from :func:`group_by_action`.
    Returns:
        ``{action: {metric: mean over its windows, ..., "windows": n_a}}``.
    """
    out = {}
    for action, idx in groups.items():
        row = {k: float(np.mean(np.asarray(v, np.float64)[idx])) for k, v in per_window.items()}
        row[COUNT_KEY] = int(len(idx))
        out[action] = row
    return out


def _metric_keys(per_action: dict[str, dict[str, float]]) -> list[str]:
    keys: list[str] = []
    for row in per_action.values():
        keys += [k for k in row if k != COUNT_KEY and k not in keys]
    return keys


def macro_average(per_action: dict[str, dict[str, float]]) -> dict[str, float]:
    """The unweighted mean over actions of each metric (every action counts once, whatever its window count);
    a metric missing in some action is averaged over the actions that have it."""
    if not per_action:
        raise ValueError("no actions to average")
    return {k: float(np.mean([row[k] for row in per_action.values() if k in row])) for k in _metric_keys(per_action)}


def window_weighted_average(per_action: dict[str, dict[str, float]]) -> dict[str, float]:
    """The mean over actions of each metric weighted by the actions' window counts: for a metric that is a
    mean over windows (ADE, FDE, APD, MMADE, MMFDE) this is the pooled value over all windows."""
    if not per_action:
        raise ValueError("no actions to average")
    out = {}
    for k in _metric_keys(per_action):
        rows = [row for row in per_action.values() if k in row]
        w = np.array([row[COUNT_KEY] for row in rows], np.float64)
        out[k] = float(np.sum(w * np.array([row[k] for row in rows])) / w.sum())
    return out


def ratios_to(per_action: dict[str, dict[str, float]], reference: dict[str, dict[str, float]]) -> dict[str, list[float]]:
    """action -> [ADE, FDE] of ``per_action`` divided by ``reference``'s for the same action, plus ``macro``: the
    unweighted mean of those ratios over actions. Both as :func:`per_action_means` gives them (``reference`` the
    zero-velocity baseline's in docs/results.md's tables)."""
    rows = {a: {"ade": r["ade"] / reference[a]["ade"], "fde": r["fde"] / reference[a]["fde"]}
            for a, r in per_action.items()}
    macro = macro_average(rows)
    return {**{a: [r["ade"], r["fde"]] for a, r in rows.items()}, "macro": [macro["ade"], macro["fde"]]}


# --- the subject split (``evaluate --split subjects``) ---------------------------------------------------
FAMILY_SEPARATOR = " @ "  # window key "walk @ bandai": the action and the family of sources its clip is from


def family_key(action: str | None, family: str) -> str:
    """The window label the subject split scores by: ``"walk @ bandai"``."""
    return f"{action or UNLABELLED}{FAMILY_SEPARATOR}{family}"


def subject_split_report(per_key: dict[str, dict[str, float]], train_actions: set[str], *,
                         family: str = "bandai") -> dict:
    """One method's rows of the subject split from its per-(action, family) means (:func:`per_action_means` of
    windows labelled by :func:`family_key`).

    - ``per_action``: each action present in training, its families merged (window-weighted, so exact for the
      per-window metrics ADE, FDE, MMADE, MMFDE, APD);
    - ``macro``: the unweighted mean over those actions;
    - ``unseen``: each test action no training clip performs, merged likewise, outside the macro;
    - ``cross_dataset``: the macro over the actions of ``family``'s held-out windows (the held-out Bandai
      performers), present in training or not; None without such windows.

    Returns:
        ``{"per_action": {action: row}, "macro": row, "unseen": {action: row}, "cross_dataset": row | None}``.
    """
    by_action: dict[str, dict[str, dict]] = {}
    for key, row in per_key.items():
        action, _, fam = key.rpartition(FAMILY_SEPARATOR)
        by_action.setdefault(action, {})[fam] = row
    merged = {a: window_weighted_average(rows) | {COUNT_KEY: int(sum(r[COUNT_KEY] for r in rows.values()))}
              for a, rows in by_action.items()}
    order = sorted(merged, key=lambda a: (-merged[a][COUNT_KEY], a))
    seen = {a: merged[a] for a in order if a in train_actions}
    unseen = {a: merged[a] for a in order if a not in train_actions}
    held = {a: rows[family] for a, rows in by_action.items() if family in rows}
    cross = None
    if held:
        cross = macro_average(held) | {COUNT_KEY: int(sum(r[COUNT_KEY] for r in held.values()))}
    return {"per_action": seen, "macro": macro_average(seen) if seen else {}, "unseen": unseen,
            "cross_dataset": cross}
