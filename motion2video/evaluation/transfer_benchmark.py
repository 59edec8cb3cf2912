"""Known-answer behaviour transfer on real motion: does a re-enacted jump jump?

Behaviours with a measurable signature (:mod:`motion2video.evaluation.signatures`) are cut from real mocap
clips (:data:`CASES`), each re-enacted from the start postures of clips of OTHER subjects
(:data:`TARGETS`), and the signature of the re-enactment is divided by the source's: 1.0 = the behaviour came
across in full, 0 = none of it. Held-out cases (clips of the pinned split's test subjects, re-enacted from
postures of other test subjects) are reported apart from training cases (training clips, training targets).

Three ways to re-enact, all from the same source window and target posture:

- ``transfer``: a behaviour model (``behavior``): z = E(source window), decoded from the target posture;
- ``analogy``: MT-VAE's A : B :: C : D (``mtvae-add``): A = the 16 frames up to the source start, B = the
  behaviour, C = the 16 frames up to the target posture; D is the re-enactment;
- ``copy``: the source window itself, moved rigidly to the target's position and heading (carries every
  signature exactly, but starts from the source's posture, not the target's).

Beside each case's own (root-path) signature, the root-relative signatures of
:data:`motion2video.evaluation.signatures.ROOT_RELATIVE_SIGNATURES` (leg extension, arm swing, knee bend,
ankle lift) of every pair, as ratios too: a re-enactment that follows the source's root path keeps a jump's
pelvis excursion while its legs and arms may do nothing.

Beside the ratios: the start-posture error (mean per-joint distance between the first generated frame and
the target posture, root-relative and heading-aligned; small = the re-enactment starts from the target) and
the bone-length spread (largest per-bone s.d. / mean length over the generated frames; 0 = rigid bones).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motion2video.evaluation import signatures as S

FPS = 25.0
CONTEXT = 16  # frames of A and C for the analogy (the models' observed length)


@dataclass(frozen=True)
class Case:
    """A behaviour window of a real clip.

    Attributes:
        behaviour: ``jump``, ``kick``, ``walk/run``, ``turn`` or ``dance/martial arts``.
        clip: path relative to the mocap folder.
        start: the window's first frame at 25 fps (its start posture), then ``horizon`` frames.
        horizon: generated frames (48 = the models' training future; 32 for clips too short for 48).
        split: ``held-out`` (test subjects of the pinned split) or ``train``.
        why: what the window holds, measured (the signature of the source window at 25 fps).
    """

    behaviour: str
    clip: str
    start: int
    horizon: int
    split: str
    why: str


SIGNATURE_OF = {"jump": "pelvis_excursion", "kick": "kick_height", "walk/run": "root_speed",
                "turn": "heading_change", "dance/martial arts": "limb_speed"}
BEHAVIOURS = tuple(SIGNATURE_OF)
RELATIVE = S.ROOT_RELATIVE_SIGNATURES
# A root-relative ratio is only read where the source moves that way at all: a source amplitude below this
# (metres) gives no ratio (NaN), e.g. the arm swing of a source whose arms hang still.
MIN_RELATIVE_AMPLITUDE = 0.05

# Chosen by manifest label, then the window with the largest signature in the clip (sliding, 25 fps,
# stride 4; evaluation.signatures.signature scores a window).
CASES = (
    # held-out: CMU subjects 2, 5, 7, 131 and 94 (Indian dance), the pinned split's test groups
    Case("jump", "cmu/02_04.bvh", 0, 48, "held-out", "jump, balance: pelvis rises and falls 0.75 m"),
    Case("jump", "cmu/131_03.bvh", 124, 48, "held-out", "hop: pelvis range 0.30 m"),
    Case("kick", "cmu/05_14.bvh", 64, 48, "held-out", "dance, arabesque: ankle 0.23 m above the knee"),
    Case("walk/run", "cmu/02_03.bvh", 0, 32, "held-out", "run/jog at 2.55 m/s (36 frames: horizon 32)"),
    Case("walk/run", "cmu/02_01.bvh", 12, 48, "held-out", "walk at 1.18 m/s"),
    Case("walk/run", "cmu/07_01.bvh", 8, 48, "held-out", "walk at 1.39 m/s"),
    Case("turn", "acrnn/indian_04.bvh", 432, 48, "held-out", "Indian dance, a full spin: heading 6.0 rad"),
    Case("turn", "cmu/131_01.bvh", 24, 48, "held-out", "start-walk-stop, turning 1.8 rad"),
    Case("dance/martial arts", "cmu/05_14.bvh", 72, 48, "held-out", "dance: wrists/ankles at 2.26 m/s"),
    Case("dance/martial arts", "acrnn/indian_04.bvh", 420, 48, "held-out", "Indian dance: limbs at 2.16 m/s"),
    # training clips
    Case("jump", "cmu/13_41.bvh", 0, 48, "train", "jump: pelvis range 0.87 m"),
    Case("jump", "cmu/13_11.bvh", 8, 48, "train", "forward jump: pelvis range 0.45 m"),
    Case("jump", "cmu/01_01.bvh", 328, 48, "train", "playground forward jumps: pelvis range 0.45 m"),
    Case("kick", "deepmimic-cmu/90_05.txt", 28, 48, "train", "jump kick: ankle 0.30 m above the knee"),
    Case("kick", "deepmimic/humanoid3d_kick.bvh", 0, 32, "train", "kick: ankle 0.11 m above the knee"),
    Case("walk/run", "cmu-bench/train/running/running_1.txt", 0, 32, "train", "run at 3.18 m/s"),
    Case("walk/run", "deepmimic-cmu/16_08.txt", 0, 32, "train", "run/jog at 2.06 m/s"),
    Case("turn", "cmu/01_01.bvh", 404, 48, "train", "turn around: heading 3.3 rad"),
    Case("turn", "deepmimic-cmu/16_52.txt", 0, 32, "train", "run, 90-degree left turn: 1.4 rad"),
    Case("dance/martial arts", "deepmimic/humanoid3d_dance_a.bvh", 0, 32, "train", "dance: limbs at 3.04 m/s"),
    Case("dance/martial arts", "acrnn/martial_04.bvh", 72, 48, "train", "martial arts: limbs at 0.99 m/s"),
)

# Start postures: (clip, frame at 25 fps, subject group). A case uses every target of its split whose
# subject differs from the source's. Frames >= 16 so that the analogy has 16 frames of C.
TARGETS = {
    "held-out": (
        ("cmu/07_03.bvh", 30, "cmu-07"),  # walking
        ("cmu/131_02.bvh", 40, "cmu-131"),  # standing before a walk
        ("acrnn/indian_06.bvh", 200, "cmu-94"),  # Indian dance
        ("cmu/02_02.bvh", 30, "cmu-02"),  # walking
        ("cmu/05_01.bvh", 30, "cmu-05"),  # walking
    ),
    "train": (
        ("cmu/01_01.bvh", 100, "cmu-01"),  # walking on the playground
        ("cmu/13_13.bvh", 20, "cmu-13"),  # standing before a jump
        ("acrnn/martial_05.bvh", 100, "cmu-135"),  # martial arts
        ("deepmimic/humanoid3d_run.bvh", 16, "deepmimic"),  # running
    ),
}

SUBJECT_OF = {  # the split group of every case clip (for "other subjects")
    "cmu/02_04.bvh": "cmu-02", "cmu/131_03.bvh": "cmu-131", "cmu/05_14.bvh": "cmu-05", "cmu/02_03.bvh": "cmu-02",
    "cmu/02_01.bvh": "cmu-02", "cmu/07_01.bvh": "cmu-07", "acrnn/indian_04.bvh": "cmu-94",
    "cmu/131_01.bvh": "cmu-131", "cmu/13_41.bvh": "cmu-13", "cmu/13_11.bvh": "cmu-13", "cmu/01_01.bvh": "cmu-01",
    "deepmimic-cmu/90_05.txt": "cmu-90", "deepmimic/humanoid3d_kick.bvh": "deepmimic",
    "cmu-bench/train/running/running_1.txt": "cmu-bench:running", "deepmimic-cmu/16_08.txt": "cmu-16",
    "deepmimic-cmu/16_52.txt": "cmu-16", "deepmimic/humanoid3d_dance_a.bvh": "deepmimic",
    "acrnn/martial_04.bvh": "cmu-135",
}


def targets_for(case: Case) -> tuple[tuple[str, int, str], ...]:
    """The target postures of ``case``: its split's targets of other subjects."""
    return tuple(t for t in TARGETS[case.split] if t[2] != SUBJECT_OF[case.clip])


@dataclass(frozen=True)
class PairResult:
    """One re-enactment of one case from one target posture.

    Attributes:
        method: ``transfer``, ``analogy`` or ``copy``.
        case: the :class:`Case`; target: (clip, frame).
        source_signature, signature: the signature of the source window and of the re-enactment.
        start_error: metres, first generated frame vs the target posture (root-relative, heading-aligned).
        bone_spread: bone-length spread over the generated frames (:func:`signatures.bone_length_spread`).
        relative: root-relative signature name -> (source's, re-enactment's) (:data:`RELATIVE`).
        posture_kept: :func:`posture_kept` of the re-enactment.
    """

    method: str
    case: Case
    target: tuple[str, int]
    source_signature: float
    signature: float
    start_error: float
    bone_spread: float
    relative: dict
    posture_kept: float = float("nan")

    @property
    def ratio(self) -> float:
        return self.signature / self.source_signature if self.source_signature > 1e-9 else float("nan")

    def relative_ratio(self, name: str) -> float:
        """Re-enactment / source of the root-relative signature ``name``; NaN when the source's amplitude is
        below :data:`MIN_RELATIVE_AMPLITUDE`."""
        src, got = self.relative[name]
        return got / src if src >= MIN_RELATIVE_AMPLITUDE else float("nan")


def score(method: str, case: Case, target: tuple[str, int], source: np.ndarray, target_posture: np.ndarray,
          reenacted: np.ndarray) -> PairResult:
    """Score one re-enactment.

    Args:
        source: (1 + H, 17, 3) the source window (its start posture first).
        target_posture: (17, 3) the posture it should start from.
        reenacted: (1 + H, 17, 3) the re-enactment (its start posture first, then H generated frames).
    """
    name = SIGNATURE_OF[case.behaviour]
    return PairResult(method=method, case=case, target=target,
                      source_signature=S.signature(name, source, FPS),
                      signature=S.signature(name, reenacted, FPS),
                      start_error=S.posture_error(reenacted[1:2], target_posture),
                      bone_spread=S.bone_length_spread(reenacted[1:]),
                      relative={r: (S.signature(r, source, FPS), S.signature(r, reenacted, FPS)) for r in RELATIVE},
                      posture_kept=posture_kept(source, target_posture, reenacted))


def posture_kept(source: np.ndarray, target_posture: np.ndarray, reenacted: np.ndarray) -> float:
    """How much of the target's own posture a re-enactment keeps: the mean per-joint distance (root-relative)
    between the re-enactment and the source moved onto the target (:func:`copy_reenactment`) over the second
    half of the generated frames, over the same distance at the start posture. About 1: it stays as different
    from the source's poses as the target's posture was; 0: it turned into the source's poses. NaN when the
    target posture equals the source's start.

    Args:
        source, reenacted: (1 + H, 17, 3), start posture first; target_posture: (17, 3).
    """
    copy = copy_reenactment(source, target_posture)
    made = np.asarray(reenacted, np.float64)
    rel = lambda x: x - x[:, :1]  # noqa: E731  root-relative
    dist = np.linalg.norm(rel(made) - rel(copy), axis=-1).mean(axis=-1)  # (1 + H,)
    if dist[0] < 1e-6:
        return float("nan")
    h = len(dist) - 1
    return float(dist[1 + h // 2:].mean() / dist[0])


def copy_reenactment(source: np.ndarray, target_posture: np.ndarray) -> np.ndarray:
    """The copy-the-source baseline: (1 + H, 17, 3) source moved rigidly (about z) so that its first root
    stands on the target's root position (x, y) facing the target's heading; heights unchanged."""
    src = np.asarray(source, np.float64)
    tgt = np.asarray(target_posture, np.float64)

    def heading(p: np.ndarray) -> float:
        hips = p[S.L_HIP, :2] - p[S.R_HIP, :2]
        return float(np.arctan2(hips[1], hips[0]))

    angle = heading(tgt) - heading(src[0])
    c, s = np.cos(angle), np.sin(angle)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    origin = np.array([src[0, 0, 0], src[0, 0, 1], 0.0])
    moved = (src - origin) @ rot.T
    moved[..., :2] += tgt[0, :2]
    return moved


def _median(x: np.ndarray) -> float:
    """Median ignoring NaN; NaN when all are NaN (no warning)."""
    x = np.asarray(x, np.float64)
    return float(np.median(x[np.isfinite(x)])) if np.isfinite(x).any() else float("nan")


def summarise(results: list[PairResult]) -> list[dict]:
    """Per (split, behaviour, method): the median ratio, its inter-quartile range, the number of pairs, the
    median start error, the median bone spread, ``relative``: the median ratio of every root-relative
    signature (NaN where no source of the behaviour moves that way, :data:`MIN_RELATIVE_AMPLITUDE`), and the
    median :func:`posture_kept`."""
    rows = []
    keys = sorted({(r.case.split, r.case.behaviour, r.method) for r in results},
                  key=lambda k: (k[0] != "held-out", BEHAVIOURS.index(k[1]), k[2]))
    for split, behaviour, method in keys:
        sel = [r for r in results if (r.case.split, r.case.behaviour, r.method) == (split, behaviour, method)]
        ratios = np.array([r.ratio for r in sel])
        rows.append({
            "split": split, "behaviour": behaviour, "method": method, "signature": SIGNATURE_OF[behaviour],
            "pairs": len(sel), "median_ratio": float(np.nanmedian(ratios)),
            "q25": float(np.nanpercentile(ratios, 25)), "q75": float(np.nanpercentile(ratios, 75)),
            "start_error": float(np.median([r.start_error for r in sel])),
            "bone_spread": float(np.median([r.bone_spread for r in sel])),
            "relative": {name: _median([r.relative_ratio(name) for r in sel]) for name in RELATIVE},
            "posture_kept": _median([r.posture_kept for r in sel]),
        })
    return rows


# --- running it ---------------------------------------------------------------------------------------


def load_clip_25(mocap: str, clip: str) -> np.ndarray:
    """(T, 17, 3) world joints of ``mocap/clip`` at 25 fps (the manifest's rate, as the corpus reads it)."""
    from pathlib import Path

    from motion2video.data import windows as W
    from motion2video.formats.mocap import load_mocap

    motion = load_mocap(Path(mocap) / clip)
    return W.resample(np.asarray(motion.joints, np.float64), motion.fps, FPS)


def _window_before(clip: np.ndarray, frame: int, length: int) -> np.ndarray:
    """(length, 17, 3): the frames up to and including ``frame``, the first frame repeated when too few."""
    idx = np.clip(np.arange(frame - length + 1, frame + 1), 0, None)
    return clip[idx]


def transfer_reenactments(bundle, sources: np.ndarray, postures: np.ndarray, *, adapt_steps: int | None = None
                          ) -> np.ndarray:
    """A behaviour model's re-enactments: sources (N, 1 + H, 17, 3), postures (N, 17, 3) -> (N, 1 + H, 17, 3)
    (the target posture, then H generated frames), as ``motion2video transfer`` makes them
    (:func:`motion2video.stages.latents.reenact_sources`: a decoder fitted for ``adapt_steps`` steps, default
    ``ADAPT_STEPS`` as the command, to each source retargeted onto its posture, all N side by side; 0: as
    trained). The sources must have one length."""
    from motion2video.stages.latents import ADAPT_STEPS, reenact_sources

    steps = ADAPT_STEPS if adapt_steps is None else adapt_steps
    return reenact_sources(bundle, np.asarray(sources), np.asarray(postures), adapt_steps=steps)[1]


def analogy_reenactments(bundle, a_b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """MT-VAE analogy re-enactments: a_b (N, 16 + H, 17, 3) (A's 16 frames ending at the source start, then
    the behaviour), c (N, 16, 17, 3) ending at the target posture -> (N, 1 + H, 17, 3)."""
    from motion2video.stages.latents import analogy_windows

    horizon = a_b.shape[1] - CONTEXT
    _, d, _, _ = analogy_windows(bundle, a_b, c, observed=CONTEXT, horizon=horizon)
    return np.concatenate([c[:, -1:], d], axis=1)


def run_benchmark(mocap: str, *, transfer=None, analogy=None, cases=CASES, adapt_steps: int | None = None
                  ) -> list[PairResult]:
    """Every case x target, re-enacted by ``transfer`` (a behaviour bundle; its decoder adapted to each source
    for ``adapt_steps`` steps, default as ``motion2video transfer``, every pair of every case fitted side by
    side), ``analogy`` (an MT-VAE bundle) and the copy baseline (either bundle may be None)."""
    clips: dict[str, np.ndarray] = {}

    def clip(name: str) -> np.ndarray:
        if name not in clips:
            clips[name] = load_clip_25(mocap, name)
        return clips[name]

    pairs = []  # (case, target, source (1 + H, 17, 3), posture (17, 3)) for every case x target
    for case in cases:
        data = clip(case.clip)
        if case.start + 1 + case.horizon > len(data):
            raise ValueError(f"{case.clip}: {len(data)} frames at 25 fps, too short for {case}")
        source = data[case.start:case.start + 1 + case.horizon]
        pairs += [(case, t, source, clip(t[0])[t[1]]) for t in targets_for(case)]
    made: dict[str, list[np.ndarray]] = {"copy": [copy_reenactment(src, post) for _, _, src, post in pairs]}
    if transfer is not None:  # the sources differ in length between cases: one fit per length, side by side
        made["transfer"] = [None] * len(pairs)
        for length in sorted({len(src) for _, _, src, _ in pairs}):
            rows = [i for i, (_, _, src, _) in enumerate(pairs) if len(src) == length]
            seqs = transfer_reenactments(transfer, np.stack([pairs[i][2] for i in rows]),
                                         np.stack([pairs[i][3] for i in rows]), adapt_steps=adapt_steps)
            for i, seq in zip(rows, seqs):
                made["transfer"][i] = seq
    if analogy is not None:
        made["analogy"] = []
        for case in cases:
            data, targets = clip(case.clip), targets_for(case)
            source = data[case.start:case.start + 1 + case.horizon]
            a = _window_before(data, case.start, CONTEXT)
            a_b = np.concatenate([a, source[1:]])[None].repeat(len(targets), axis=0)
            c = np.stack([_window_before(clip(t[0]), t[1], CONTEXT) for t in targets])
            made["analogy"] += list(analogy_reenactments(analogy, a_b, c))
    results: list[PairResult] = []
    for (case, target, source, posture), *seqs in zip(pairs, *made.values()):
        results += [score(method, case, (target[0], target[1]), source, posture, seq)
                    for method, seq in zip(made, seqs)]
    return results
