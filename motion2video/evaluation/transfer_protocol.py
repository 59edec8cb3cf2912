"""Behaviour transfer's protocol (Blattmann et al., CVPR 2021, Table 1 / Table 3), for
``scripts/make_results.py transfer``: on held-out windows, each source behaviour x_beta is re-enacted from the
start posture of a window of a DIFFERENT clip:

- TDE(T): mean squared error between re-enactment x_R and source x_beta at frame T (root-relative joints,
  cm^2 per coordinate); a copying model drives it to 0, a model ignoring z keeps it large;
- d_beta: Euclidean distance between z(x_beta) and z(x_R) (re-encoding the re-enactment from its own start);
- RE(T): mean squared error of a ridge regression from z(x_beta) to the posture x_beta[T] (fitted on
  training windows), i.e. how much posture the representation carries;
- realism (Table 3): the two-sample test of :mod:`motion2video.evaluation.realism` between the held-out
  ground-truth futures and the reconstructions ("self"), transfers, prior samples and flow samples of the
  same windows (cross-validated held-out accuracy of a logistic regression on per-window motion features;
  0.5 = indistinguishable), with its real-vs-real control (two halves of the windows, about 0.5). It replaced
  the full-descriptor ridge classifier (``metrics.quality``), which told real motion of different people
  apart (0.99) and so measured who moves, not whether the motion is real.
MT-VAE enters through analogy: z = E(obs_source, future_source), x_R = D(obs_target, z).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import torch

from motion2video.evaluation import metrics as M
from motion2video.models.checkpoint import ModelBundle
from motion2video.core.errors import InputError
from motion2video.data import windows as W
from motion2video.data.dataset import WindowSet
from motion2video.evaluation.realism import point_dim, two_sample_realism
from motion2video.models.behavior import BehaviorModel
from motion2video.stages.sampling import as_model_input, sample_futures

TABLE1_TIMESTEPS = (1, 10, 20, 30, 40)
CM2 = 1.0e4  # m^2 -> cm^2


def transfer_pairs(clip_names: tuple[str, ...], *, seed: int) -> np.ndarray:
    """For each window, the index of a target window from a DIFFERENT clip (uniform, seeded): (N,) int.

    Raises ValueError when all windows come from one clip.
    """
    names = np.asarray(clip_names)
    if len(set(names.tolist())) < 2:
        raise ValueError("behaviour transfer pairs need windows from at least two clips")
    rng = np.random.default_rng(seed)
    out = np.empty(len(names), np.int64)
    for i, name in enumerate(names):
        others = np.flatnonzero(names != name)
        out[i] = others[rng.integers(len(others))]
    return out


@dataclass
class TransferScores:
    """Table 1 and Table 3 numbers of one model.

    Attributes:
        tde: T -> transfer displacement error (cm^2 per coordinate, root-relative joints).
        re: T -> posture-regression error from z (cm^2 per coordinate), held-out windows.
        tde_se, re_se: T -> standard error of those means over the windows.
        d_beta: mean and standard deviation of ||z(x_beta) - z(x_R)||.
        d_random: the same between z(x_beta) and the behaviour of the target window the posture came from
            (an unrelated behaviour): the scale d_beta is read against (d_beta / d_random < 1 when the
            re-enactment kept the source's behaviour better than an unrelated clip's).
        realism: origin (``self``, ``transfer``, ``prior``, ``flow``) -> two-sample test accuracy between the
            real and the generated futures of the same windows (0.5 = indistinguishable from real, 1 = always
            told apart; :func:`motion2video.evaluation.realism.two_sample_realism`).
        realism_control: the same test on real against real (two halves of the windows): about 0.5.
        realism_poses: a ridge real/fake classifier on poses alone (:func:`pose_descriptor`).
        motion: ``real`` and every origin -> (mean |velocity|, mean |acceleration|) of the feature vector per
            frame (metres per frame, per frame^2): how lively the motion is.
        windows: number of held-out windows.
    """

    tde: dict[int, float]
    re: dict[int, float]
    tde_se: dict[int, float]
    re_se: dict[int, float]
    d_beta: M.MeanStd
    d_random: M.MeanStd
    realism: dict[str, float]
    realism_control: float
    realism_poses: dict[str, float]
    motion: dict[str, tuple[float, float]]
    windows: int

    def to_json(self) -> dict:
        return {"tde_cm2": self.tde, "re_cm2": self.re, "tde_se_cm2": self.tde_se, "re_se_cm2": self.re_se,
                "d_beta": dataclasses.asdict(self.d_beta),
                "d_random": dataclasses.asdict(self.d_random), "realism_accuracy": self.realism,
                "realism_control": self.realism_control,
                "realism_accuracy_poses": self.realism_poses, "motion_per_frame": self.motion,
                "windows": self.windows}


def pose_descriptor(seq: np.ndarray) -> np.ndarray:
    """Poses only: every 4th frame of (N, T, F) sequences, flattened -> (N, ceil(T / 4) * F)."""
    s = np.asarray(seq, np.float64)
    return s[:, ::4].reshape(len(s), -1)


def classifier_accuracy(real: np.ndarray, fake: np.ndarray, *, l2: float = 1.0) -> float:
    """Test accuracy of a ridge real/fake classifier on descriptors (N, P) and (M, P); even items train, odd
    items test (as :func:`motion2video.evaluation.metrics.quality`, on any descriptor)."""
    x = np.concatenate([real, fake])
    y = np.concatenate([np.ones(len(real), np.int64), np.zeros(len(fake), np.int64)])
    train = np.concatenate([np.arange(len(real)) % 2 == 0, np.arange(len(fake)) % 2 == 0])
    clf = M.fit_ridge_classifier(x[train], y[train], l2=l2)
    return float(np.mean(clf.predict(x[~train]) == y[~train]))


motion_liveliness = M.liveliness  # (mean |velocity|, mean |acceleration|) of (N, T, F) sequences, per frame


@dataclass(frozen=True)
class SampleRealism:
    """How lively and how realistic a model's sampled futures are, on held-out windows.

    Attributes:
        real, samples: (mean |velocity|, mean |acceleration|) of the feature vector per frame of the
            ground-truth futures and of all K samples per window (:func:`motion_liveliness`).
        realism: two-sample test accuracy (:func:`motion2video.evaluation.realism.two_sample_realism`)
            between the ground truth and one sample per window of the same windows (sample ``i mod K`` for
            window i, so that a sampler whose K outputs differ in kind, DLow's maps, is seen whole);
            realism_control: its real-vs-real control (about 0.5); realism_by_family: the test on speeds,
            accelerations or positional spreads alone (:attr:`TwoSampleRealism.by_family`);
            realism_poses: a ridge real/fake classifier on poses alone, the same pairs.
        windows, samples_per_window: N and K.
    """

    real: tuple[float, float]
    samples: tuple[float, float]
    realism: float
    realism_control: float
    realism_by_family: dict
    realism_poses: float
    windows: int
    samples_per_window: int


def sample_realism(bundle: ModelBundle, test: WindowSet, *, samples: int = 10, seed: int = 0) -> SampleRealism:
    """:class:`SampleRealism` of any sampling model (``model.sample``) on the windows ``test``."""
    to = test.observed
    horizon = test.features.shape[1] - to
    futures = sample_futures(bundle.model, test.obs, num_samples=samples, horizon=horizon, seed=seed)  # (N, K, T, F)
    fake_all = bundle.stats.denormalize(futures)
    real = bundle.stats.denormalize(test.future)  # (N, T, F)
    rows = np.arange(len(real))
    one = fake_all[rows, rows % samples]  # (N, T, F)
    every = fake_all.reshape(-1, horizon, real.shape[-1])  # (N*K, T, F)
    test = two_sample_realism(real, one, dim=point_dim(bundle.layout.kind), seed=seed)
    return SampleRealism(real=motion_liveliness(real), samples=motion_liveliness(every),
                         realism=test.accuracy, realism_control=test.control, realism_by_family=test.by_family,
                         realism_poses=classifier_accuracy(pose_descriptor(real), pose_descriptor(one)),
                         windows=len(real), samples_per_window=samples)


def _posture(bundle: ModelBundle, features: np.ndarray) -> np.ndarray:
    """Normalised features (..., F) -> root-relative posture vectors (..., M), metres."""
    return W.metric_vectors(bundle.stats.denormalize(features), bundle.layout)


def regression_errors(z_train: np.ndarray, posture_train: np.ndarray, z_test: np.ndarray,
                      posture_test: np.ndarray, *, l2: float = 1.0) -> np.ndarray:
    """Per test item, the mean squared error (per coordinate) of a ridge regression z -> posture fitted on the
    training pairs (standardised z, closed form). z: (N, Z); posture: (N, M). Returns (N_test,)."""
    zt, zs = np.asarray(z_train, np.float64), np.asarray(z_test, np.float64)
    mean, scale = zt.mean(0), zt.std(0) + 1e-8
    a = np.concatenate([(zt - mean) / scale, np.ones((len(zt), 1))], axis=1)  # (N, Z + 1)
    reg = l2 * np.eye(a.shape[1])
    reg[-1, -1] = 0.0
    w = np.linalg.solve(a.T @ a + reg, a.T @ np.asarray(posture_train, np.float64))  # (Z + 1, M)
    pred = np.concatenate([(zs - mean) / scale, np.ones((len(zs), 1))], axis=1) @ w
    return ((pred - posture_test) ** 2).mean(axis=1)


def regression_error(z_train: np.ndarray, posture_train: np.ndarray, z_test: np.ndarray,
                     posture_test: np.ndarray, *, l2: float = 1.0) -> float:
    """RE: the mean of :func:`regression_errors` over the test items."""
    return float(regression_errors(z_train, posture_train, z_test, posture_test, l2=l2).mean())


def _mean_se(x: np.ndarray) -> tuple[float, float]:
    """Mean and standard error of the mean of (N,) values."""
    x = np.asarray(x, np.float64)
    return float(x.mean()), float(x.std(ddof=1) / np.sqrt(len(x))) if len(x) > 1 else 0.0


@torch.no_grad()
def _latents_and_transfers(bundle: ModelBundle, obs: np.ndarray, fut: np.ndarray, target_obs: np.ndarray,
                           *, batch: int = 256) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """z(x_beta), the self-reconstruction, the transfer x_R and z(x_R), batched.

    Behaviour models: z from [x_t, x_beta] and re-enactment from the target's last observed posture;
    other latent models (MT-VAE analogy): z = E(obs, future) and x_R = D(target obs, z). A behaviour model
    with ``root_trajectory`` reconstructs and re-enacts along the source's root path, as ``transfer`` does.
    """
    model = bundle.model
    model.eval()
    horizon = fut.shape[1]
    zs, selfs, trans, zr = [], [], [], []
    for i in range(0, len(obs), batch):
        o, f, t = (as_model_input(x[i:i + batch], model) for x in (obs, fut, target_obs))
        z = model.encode(o, f).mu
        if isinstance(model, BehaviorModel) and model.config.root_trajectory:
            # as `motion2video transfer`: enacted along the source's root path (height shifted to the start)
            r = model.config.root_dims
            path = f[..., -r:]
            shifted = path.clone()
            shifted[..., -1] += (t[:, -1, -1] - o[:, -1, -1])[:, None]
            rec = model.transfer(z, o[:, -1], horizon, root=path)
            x_r = model.transfer(z, t[:, -1], horizon, root=shifted)
        else:
            rec = model.decode(o, z, horizon=horizon)
            x_r = model.decode(t, z, horizon=horizon)
        z_r = model.encode(t, x_r).mu
        for acc, v in ((zs, z), (selfs, rec), (trans, x_r), (zr, z_r)):
            acc.append(v.cpu().numpy())
    return tuple(np.concatenate(a) for a in (zs, selfs, trans, zr))


def evaluate_transfer(bundle: ModelBundle, test: WindowSet, train: WindowSet, *, pairs: np.ndarray,
                      timesteps: tuple[int, ...] = TABLE1_TIMESTEPS, seed: int = 0) -> TransferScores:
    """The behaviour-transfer protocol (module docstring) for one latent model on held-out windows.

    Args:
        bundle: a ``behavior`` model (z from the behaviour sequence, re-enacted from a posture) or another
            latent model with ``encode`` / ``decode`` (MT-VAE: analogy from the target's observed window).
        test: held-out windows; train: training windows (fit the RE regressor).
        pairs: (N,) target window per test window (:func:`transfer_pairs`).
        timesteps: 1-based frames of the generated future at which TDE and RE are measured.
        seed: seeds the prior / flow samples.
    """
    if not (hasattr(bundle.model, "encode") and hasattr(bundle.model, "decode")):
        raise InputError(f"{bundle.label} has no latent space (encode / decode) to transfer with")
    to = test.observed
    horizon = test.features.shape[1] - to
    if max(timesteps) > horizon:
        raise ValueError(f"timestep {max(timesteps)} is beyond the {horizon}-frame future")
    idx = np.asarray(timesteps) - 1
    obs, fut = test.obs, test.future
    z, rec, x_r, z_r = _latents_and_transfers(bundle, obs, fut, obs[pairs])
    gt = _posture(bundle, fut)  # (N, Tf, M)
    pred = _posture(bundle, x_r)
    tde = M.transfer_displacement_error(pred, gt, timesteps=idx) * CM2
    tde_se = {t: _mean_se(((pred[:, t - 1] - gt[:, t - 1]) ** 2).mean(axis=1) * CM2)[1] for t in timesteps}
    z_train = _latents_and_transfers(bundle, train.obs, train.future, train.obs)[0]
    gt_train = _posture(bundle, train.future)
    re_stats = {t: _mean_se(regression_errors(z_train, gt_train[:, t - 1], z, gt[:, t - 1]) * CM2) for t in timesteps}
    real = bundle.stats.denormalize(fut)  # (N, Tf, F) whole features: pose and root trajectory
    fakes = {"self": rec, "transfer": x_r}
    gen = torch.Generator().manual_seed(int(seed))
    model = bundle.model
    with torch.no_grad():
        o = as_model_input(obs, model)
        if isinstance(model, BehaviorModel):
            fakes["prior"] = model.sample(o, num_samples=1, horizon=horizon, generator=gen,
                                          use_flow=False)[:, 0].cpu().numpy()
            if bool(model.flow_fitted):
                fakes["flow"] = model.sample(o, num_samples=1, horizon=horizon, generator=gen,
                                             use_flow=True)[:, 0].cpu().numpy()
        else:
            fakes["prior"] = model.sample(o, num_samples=1, horizon=horizon, generator=gen)[:, 0].cpu().numpy()
    fakes = {k: bundle.stats.denormalize(v) for k, v in fakes.items()}
    dim = point_dim(bundle.layout.kind)
    tests = {k: two_sample_realism(real, v, dim=dim, seed=seed) for k, v in fakes.items()}
    realism = {k: t.accuracy for k, t in tests.items()}
    realism_poses = {k: classifier_accuracy(pose_descriptor(real), pose_descriptor(v)) for k, v in fakes.items()}
    motion = {"real": motion_liveliness(real), **{k: motion_liveliness(v) for k, v in fakes.items()}}
    return TransferScores(tde={t: float(v) for t, v in zip(timesteps, tde)},
                          re={t: m for t, (m, _) in re_stats.items()}, tde_se=tde_se,
                          re_se={t: se for t, (_, se) in re_stats.items()},
                          d_beta=M.latent_distance(z, z_r), d_random=M.latent_distance(z, z[pairs]),
                          realism=realism, realism_control=next(iter(tests.values())).control,
                          realism_poses=realism_poses, motion=motion, windows=len(obs))
