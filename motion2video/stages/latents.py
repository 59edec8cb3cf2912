"""Encode and decode with latent motion models: the behaviour latents and re-enactment of behaviour transfer,
and the A : B :: C : D analogy windows. Both transfer and analogy (and their evaluation protocols) use these.

Sequences are encoded exactly like training windows (:mod:`motion2video.data.windows`, the checkpoint's
normalisation) and decoded back to display coordinates: world joints (body3d), virtual-camera pixels
(body2d) or face parameters.
"""

from __future__ import annotations

import copy
import dataclasses

import numpy as np
import torch

from motion2video.models.checkpoint import ModelBundle
from motion2video.core.errors import InputError
from motion2video.data import windows as W
from motion2video.data.dataset import DatasetConfig, decode_samples, encode_windows
from motion2video.models.behavior import BehaviorModel
from motion2video.stages.sampling import as_model_input, keep_bone_lengths


def encode_sequences(bundle: ModelBundle, sequences: np.ndarray) -> tuple[np.ndarray, W.WindowFrame | None]:
    """Behaviour sequences -> normalised features, each anchored at its FIRST frame.

    Args:
        sequences: (N, T, 17, 3) world joints or (N, T, 58) face parameters, at the model's rate.
    Returns:
        (N, T, F) float32 normalised features and the window frames (None for faces).
    """
    cfg = bundle.data_config
    layout = cfg.feature_layout
    if layout.kind == "face":
        return bundle.stats.normalize(np.asarray(sequences, np.float64)), None
    raw, frame = W.body_window_features(np.asarray(sequences), layout=layout, anchor=0,
                                        canonical_heading=cfg.canonical_heading)
    return bundle.stats.normalize(raw), frame


def decode_sequences(bundle: ModelBundle, features: np.ndarray, frame: W.WindowFrame | None) -> np.ndarray:
    """Normalised features (N, K, T, F) -> display coordinates: (N, K, T, 17, 3) world joints, (N, K, T,
    17, 2) virtual-camera pixels (body2d) or (N, K, T, 58) face parameters."""
    return decode_samples(features, config=bundle.data_config, stats=bundle.stats, frame=frame)


def behavior_model(bundle: ModelBundle) -> BehaviorModel:
    """The bundle's model when it is a behaviour model; InputError otherwise."""
    if not isinstance(bundle.model, BehaviorModel):
        raise InputError(f"behaviour transfer needs a 'behavior' model (behaviour encoder + posture-conditioned "
                         f"decoder), but {bundle.label} is a {bundle.name!r} model", bundle.path or bundle.name)
    return bundle.model


@torch.no_grad()
def behavior_latents(model: BehaviorModel, features: np.ndarray) -> np.ndarray:
    """Posterior means z_beta of normalised behaviour sequences (N, T, F) -> (N, Z) float32."""
    model.eval()
    return model.behavior_latent(as_model_input(features, model)).cpu().numpy()


def rigid_bones(layout: str, sequences: np.ndarray) -> np.ndarray:
    """Re-enactments with the bone lengths of their start posture: (K, 1 + H, 17, 3) world joints, every
    frame's bones rescaled along their own directions to frame 0's lengths (pelvis, root trajectory and joint
    directions kept; :func:`motion2video.core.skeletons.with_bone_lengths`). The decoder predicts joint
    positions, not rotations, so its bones stretch by several per cent without this. Other layouts (2D
    pixels, faces) are returned as they are. The generated frames' ankles are then kept at or above the
    start posture's lower ankle (:func:`motion2video.core.skeletons.feet_above`, leg IK): a pelvis that drops
    bends the knees instead of pushing the feet into the ground."""
    if layout != "body3d":
        return sequences
    from motion2video.core.skeletons import L_ANKLE, R_ANKLE, feet_above

    seq = np.asarray(sequences)
    out = []
    for s in seq:
        rigid = keep_bone_lengths(s, s[0])
        floor = float(min(s[0, R_ANKLE, 2], s[0, L_ANKLE, 2]))  # the start posture's lower ankle
        out.append(np.concatenate([rigid[:1], feet_above(rigid[1:], floor)]))
    return np.stack(out).astype(seq.dtype, copy=False)


def behavior_root(model: BehaviorModel, source: np.ndarray, start: np.ndarray) -> np.ndarray | None:
    """The root trajectory a ``root_trajectory`` behaviour model re-enacts along, or None for other models.

    Args:
        source: (N, 1 + H, F) normalised behaviour sequences (each anchored at its first frame).
        start: (N, F) normalised start postures of the re-enactments.
    Returns:
        (N, H, R) the source's root features after its start (x, y relative to its start in its heading frame,
        which is the same relative path in the target's heading frame), its height shifted by the difference
        of the start heights (a jump rises as high above the target's start as above the source's).
    """
    c = model.config
    if not getattr(c, "root_trajectory", False):
        return None
    r = c.root_dims
    root = np.array(source[:, 1:, -r:], np.float32, copy=True)
    root[..., -1] += (start[:, -1] - source[:, 0, -1])[:, None]
    return root


# Test-time adaptation of the behaviour decoder to one source (:func:`adapt_to_source`). Chosen on the transfer
# benchmark's TRAINING cases (transfer_benchmark.CASES, split "train"; 2026-11-26): the mean |log ratio| over their
# behaviour and root-relative signatures was 0.389 as trained, 0.253 / 0.203 / 0.198 / 0.199 / 0.187 after 25 / 50 /
# 100 / 200 / 300 Adam steps at 1e-3 (measured on the transfer benchmark); 300 is the best of those (about 6 s
# per source on one CPU thread). The step count was kept when the fit's goal became the source retargeted onto the
# target (:func:`reenactment_goal`); a fit from the source's own start reproduced the source after 300 steps as
# closely as after 1000 (docs/results.md, "Transfer from any posture").
ADAPT_STEPS = 300
ADAPT_LR = 1e-3


def adapt_to_sources(model: BehaviorModel, sources: np.ndarray, z: np.ndarray, *, steps: int = ADAPT_STEPS,
                     lr: float = ADAPT_LR) -> list[BehaviorModel]:
    """Copies of ``model``, the decoder of copy i fine-tuned to enact ``sources[i]`` from its own first frame.

    The trained decoder averages rare, large limb motions away: re-enacted from another posture, a held-out kick
    kept 0.23 of its ankle lift relative to the pelvis, and refining z alone did not bring it back
    (docs/results_transfer.md). Here z (the encoder's behaviour of the source) stays fixed and only the decoder's
    weights move, by ``steps`` Adam steps on the model's own reconstruction error of the source (its root path
    given, as in a re-enactment). ``transfer`` passes the source retargeted onto the target's posture
    (:func:`reenactment_goal`), so the decoder is fitted from the start it is then run from: the behaviour is the
    source's, the start is the target's. Deterministic: no noise, the same steps for the same inputs.

    Several decoders are fitted side by side: their weights stacked, one step of all N run by ``torch.func.vmap``
    (3.2x faster per source than one at a time on one CPU thread over 8 sources, ``scripts/bench.py
    transfer-fit``). Each copy's loss depends on its own weights only and Adam updates every weight from its own
    gradient, so each copy takes the steps it would take alone. Only the stacked arithmetic rounds differently, and
    300 Adam steps carry that some way, as they would a change of thread count: over 8 held-out pairs the re-enacted joints lay 2 mm
    from those of fits alone on average, 8 cm at the worst joint and frame. One source is fitted alone.

    Args:
        model: a trained behaviour model (left unchanged).
        sources: (N, 1 + H, F) normalised behaviour sequences, each anchored at its first frame
            (:func:`encode_sequences`).
        z: (N, Z) their behaviour latents (:func:`behavior_latents`).
        steps: Adam steps; 0 gives ``model`` itself N times.
        lr: Adam's learning rate.
    Returns:
        N adapted copies (eval mode, no gradients), or ``[model] * N`` for ``steps`` 0.
    """
    if steps < 0:
        raise ValueError(f"steps must be >= 0, got {steps}")
    if steps == 0:
        return [model] * len(sources)
    seq, latent = as_model_input(sources, model), as_model_input(z, model)
    start, future = seq[:, 0], seq[:, 1:]
    c = model.config
    root = future[..., -c.root_dims:] if getattr(c, "root_trajectory", False) else None
    if len(sources) == 1:  # one decoder needs no stacking (vmap's bookkeeping would cost it half as much again)
        adapted = _frozen_copy(model)
        weights = list(adapted.decoder.parameters())
        for w in weights:
            w.requires_grad_(True)
        _adam(weights, lambda: adapted.reconstruction_error(
            adapted.transfer(latent, start, future.shape[1], root=root), future), steps=steps, lr=lr)
        return [adapted.requires_grad_(False)]
    from torch.func import functional_call, stack_module_state, vmap

    decoder = _frozen_copy(model).decoder
    stacked, buffers = stack_module_state([decoder] * len(sources))  # name -> (N, ...): a copy per source
    stacked = {name: w.detach().clone().requires_grad_(True) for name, w in stacked.items()}

    def error(w, b, z_i, start_i, future_i, root_i):  # one source: its own decoder's reconstruction error
        args = {"horizon": future_i.shape[0]} | ({} if root_i is None else {"root": root_i[None]})
        pred = functional_call(decoder, (w, b), (z_i[None], start_i[None]), args)
        return model.reconstruction_error(pred, future_i[None])

    errors = vmap(error, in_dims=(0, 0, 0, 0, 0, None if root is None else 0))
    _adam(list(stacked.values()), lambda: errors(stacked, buffers, latent, start, future, root).sum(),
          steps=steps, lr=lr)
    adapted = []
    for i in range(len(sources)):
        copy_i = _frozen_copy(model)
        copy_i.decoder.load_state_dict({name: w[i].detach() for name, w in stacked.items()})
        adapted.append(copy_i)
    return adapted


def _frozen_copy(model: BehaviorModel) -> BehaviorModel:
    """A deep copy in eval mode (the decoder's layers behave alike in both modes; eval keeps the buffers, such
    as gamma_KL, still) with no gradients."""
    out = copy.deepcopy(model)
    out.eval()
    return out.requires_grad_(False)


def _adam(weights: list[torch.Tensor], loss, *, steps: int, lr: float) -> None:
    """``steps`` Adam steps on ``weights`` (tensors that require gradients) down the scalar ``loss()``."""
    optimiser = torch.optim.Adam(weights, lr=lr)
    with torch.enable_grad():
        for _ in range(int(steps)):
            optimiser.zero_grad()
            loss().backward()
            optimiser.step()


def adapt_to_source(model: BehaviorModel, source: np.ndarray, z: np.ndarray, *, steps: int = ADAPT_STEPS,
                    lr: float = ADAPT_LR) -> BehaviorModel:
    """:func:`adapt_to_sources` of one source: ``source`` (1, 1 + H, F), ``z`` (1, Z) -> the adapted copy (or
    ``model`` itself for ``steps`` 0)."""
    if len(source) != 1:
        raise ValueError(f"one source at a time, got {len(source)}: adapt_to_sources fits several")
    return adapt_to_sources(model, source, z, steps=steps, lr=lr)[0]


# How long the target's posture takes to give way to the source's limb motion in a retargeted goal
# (:func:`reenactment_goal`): about half a walking step, set once from that and not tuned on the clips scored.
BLEND_SECONDS = 0.4


def reenactment_goal(bundle: ModelBundle, sources: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """What a re-enactment should be, as normalised features: the sources' root-relative limb motion and root
    path retargeted onto the start postures (:func:`motion2video.core.retarget.retarget_motion`: the start's
    bone lengths, the start posture blended into the source's over :data:`BLEND_SECONDS`), for 3D bodies.

    Fitting the decoder to the source from the source's OWN start (as it was trained) did not carry over to
    another start: from a walker's posture an adapted decoder swung the arms 0.29-0.39 of a held-out jump's and
    bent the knee of a kick 0.50 of the source's, with 300 or 1000 steps alike, while from the source's own
    start it reproduced all of them (0.92-1.03; docs/results.md). The decoder is therefore fitted to the
    re-enactment it is asked for, from the start it is run from. Other layouts (2D pixels, faces) have no
    skeleton to retarget onto: their goal is the source itself.

    Args:
        sources: (N, 1 + H, 17, 3) world joints (or (N, 1 + H, ...) other layouts), start posture first.
        starts: (N, 17, 3) the target postures.
    Returns:
        (N, 1 + H, F) float32 normalised features, each anchored at its first frame (:func:`encode_sequences`);
        for 3D bodies the first frame is the target's posture.
    """
    if bundle.data_config.layout != "body3d":
        return encode_sequences(bundle, sources)[0]
    from motion2video.core.retarget import retarget_motion

    blend = int(round(BLEND_SECONDS * bundle.data_config.fps))
    goals = np.stack([retarget_motion(s, p, blend_frames=blend) for s, p in zip(sources, starts)])
    return encode_sequences(bundle, goals)[0]


def reenact_sources(bundle: ModelBundle, sources: np.ndarray, starts: np.ndarray, *,
                    adapt_steps: int = ADAPT_STEPS) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Re-enact behaviour sources, each from its own start posture, as ``motion2video transfer`` does: z = the
    encoder's behaviour of the source; a copy of the decoder fitted for ``adapt_steps`` steps to the source
    retargeted onto its start (:func:`reenactment_goal`, :func:`adapt_to_sources`, all N side by side; 0: the
    decoder as trained), then run from the start along the goal's root path; 3D bodies keep the start's bone
    lengths (:func:`rigid_bones`).

    Args:
        sources: (N, 1 + H, ...) display coordinates at the model's rate (world joints, pixels or face
            parameters), each its start posture first.
        starts: (N, ...) the target postures, in the same coordinates.
    Returns:
        z (N, Z); the re-enactments (N, 1 + H, ...) (the start, then H generated frames); the sources as the
        model reads them back (N, 1 + H, ...) (for display).
    """
    model = behavior_model(bundle)
    horizon = sources.shape[1] - 1
    src_feats, src_frame = encode_sequences(bundle, sources)  # (N, 1+H, F)
    tgt_feats, tgt_frame = encode_sequences(bundle, starts[:, None])  # (N, 1, F)
    z = behavior_latents(model, src_feats)  # (N, Z)
    goals = reenactment_goal(bundle, sources, starts)  # (N, 1+H, F)
    fitted = adapt_to_sources(model, goals, z, steps=adapt_steps)
    gen = np.concatenate([
        reenact(m, z[i:i + 1], tgt_feats[i:i + 1, 0], horizon=horizon,
                root=behavior_root(m, goals[i:i + 1], tgt_feats[i:i + 1, 0]))
        for i, m in enumerate(fitted)])  # (N, H, F)
    seq = np.concatenate([tgt_feats, gen], axis=1)  # (N, 1+H, F)
    reenacted = rigid_bones(bundle.data_config.layout, decode_sequences(bundle, seq[:, None], tgt_frame)[:, 0])
    shown = decode_sequences(bundle, src_feats[:, None], src_frame)[:, 0]
    return z, reenacted, shown


def reenact_source(bundle: ModelBundle, source: np.ndarray, start: np.ndarray, *, adapt_steps: int = ADAPT_STEPS
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`reenact_sources` of one source (1 + H, ...) from one start posture (...): z (1, Z), the
    re-enactment (1, 1 + H, ...), the source as the model reads it back (1 + H, ...)."""
    z, reenacted, shown = reenact_sources(bundle, source[None], start[None], adapt_steps=adapt_steps)
    return z, reenacted, shown[0]


@torch.no_grad()
def reenact(model: BehaviorModel, z: np.ndarray, start: np.ndarray, *, horizon: int,
            root: np.ndarray | None = None) -> np.ndarray:
    """Enact behaviours z (N, Z) from normalised start postures (N, F): (N, horizon, F) float32, along the root
    trajectory ``root`` (N, horizon, R) for a ``root_trajectory`` model (:func:`behavior_root`)."""
    model.eval()
    r = None if root is None else as_model_input(root, model)
    return model.transfer(as_model_input(z, model), as_model_input(start, model), horizon, root=r).cpu().numpy()


def analogy_model(bundle: ModelBundle) -> torch.nn.Module:
    """The bundle's model when it has a latent transformation space (encode + decode); InputError otherwise."""
    model = bundle.model
    if bundle.kind in ("deterministic", "baseline") or not (hasattr(model, "encode") and hasattr(model, "decode")):
        raise InputError(f"analogy needs a latent-variable model with a transformation encoder (mtvae-add, "
                         f"mtvae-concat, cvae, lcpvae, behavior), but {bundle.label} is a {bundle.kind} "
                         f"{bundle.name!r} model "
                         "without one", bundle.path or bundle.name)
    return model


def stitch_after(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Place body window ``b`` right after window ``a``.

    Args:
        a: (To >= 2, 17, 3) world joints; b: (Tf, 17, 3) world joints (anywhere, any heading).
    Returns:
        (Tf, 17, 3) float64: ``b`` rotated about z so its first frame's heading is ``a``'s last, and moved so
        its first root continues ``a``'s last root step (heights unchanged).
    """
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    frame_a = W.canonical_frame(a[None], anchor=a.shape[0] - 1)
    frame_b = W.canonical_frame(b[None], anchor=0)
    placed = W.from_canonical(W.to_canonical(b[None], frame_b), frame_a)[0]  # b[0]'s root on a[-1]'s root
    placed[..., :2] += a[-1, 0, :2] - a[-2, 0, :2]
    return placed


def window_config(bundle: ModelBundle, observed: int) -> DatasetConfig:
    if observed < 2:
        raise InputError(f"--observed must be >= 2 frames, got {observed}")
    return dataclasses.replace(bundle.data_config, observed=int(observed))


@torch.no_grad()
def analogy_windows(bundle: ModelBundle, ab: np.ndarray, c: np.ndarray, *, observed: int,
                    horizon: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Batched analogy on raw windows.

    Args:
        ab: (N, observed + Tf, 17, 3) world joints or (N, observed + Tf, 58) face parameters: A then B.
        c: (N, observed, ...) the C windows.
        horizon: frames of D.
    Returns:
        z (N, Z) posterior means of A -> B; D (N, horizon, ...) in C's coordinates; A -> B and C -> D in
        display coordinates, (N, observed + Tf, ...) and (N, observed + horizon, ...).
    """
    model = analogy_model(bundle)
    model.eval()
    cfg = window_config(bundle, observed)
    raw_ab, frame_ab = encode_windows(np.asarray(ab), config=cfg)  # anchored at A's last frame
    raw_c, frame_c = encode_windows(np.asarray(c), config=cfg)  # anchored at C's last frame
    f_ab, f_c = bundle.stats.normalize(raw_ab), bundle.stats.normalize(raw_c)
    device = next(model.parameters()).device
    t_ab, t_c = torch.from_numpy(f_ab).to(device), torch.from_numpy(f_c).to(device)
    z = model.encode(t_ab[:, :observed], t_ab[:, observed:]).mu  # (N, Z)
    d = model.decode(t_c, z, horizon=horizon).cpu().numpy()  # (N, H, F)
    cd = np.concatenate([f_c, d], axis=1)  # (N, To + H, F)
    shown_ab = decode_sequences(bundle, f_ab[:, None], frame_ab)[:, 0]
    shown_cd = decode_sequences(bundle, cd[:, None], frame_c)[:, 0]
    return z.cpu().numpy(), shown_cd[:, observed:], shown_ab, shown_cd
