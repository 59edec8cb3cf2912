"""A body frame generator that moves the reference person along the pose instead of repainting it.

From the reference and target 2D joints (H36M-17, pixels) it builds a dense backward motion field, in the
spirit of part-based pose transfer (per-limb affine transforms: Siarohin et al. 2018; layered parts with a
separate background: Balakrishnan et al. 2018; a keypoint-driven dense field with occlusion: Siarohin et al.
2019):

1. *Parts* (:data:`SEGMENT_PARTS` + the torso + the background): each limb segment gets a transform taking
   target pixels to reference pixels (rotate with the bone, stretch along it by the ratio of its 2D
   lengths, across it by the torso's scale); the torso gets a similarity fitted to its seven joints; the
   background is the identity.
2. *Prior masks*: a Gaussian of the distance to each part's target segment(s) gives soft part logits; a
   small motion network adds corrections (its last layer starts at zero, so the untrained model warps by
   the prior alone). The backward flow is the mask-weighted sum of the parts' maps.
3. The reference image and its encoder features at every level are warped by that flow
   (``grid_sample``); a U-Net decoder with a target-pose encoder predicts an inpainting RGB and a
   visibility mask ``v``; the output is ``v * warped_reference + (1 - v) * inpainting``: where the
   reference shows the pixel, it is copied (sharp), and only what it does not show is painted.

Inference (:meth:`WarpGenerator.encode_reference` / :meth:`WarpGenerator.decode`) works on a
person-centred square crop holding both poses, generated at the model's size and pasted back into the
full-resolution reference with a soft mask around the two people, so the background keeps its resolution.

Images in the network are float (B, 3, H, W) in [0, 1]; points are pixels (x right, y down, pixel centres
at integer + 0.5, as the shared camera projects them).
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

from motion2video.core.errors import InputError

NUM_JOINTS = 17
# Limb parts: (name, joint a, joint b); the transform follows the segment a -> b.
SEGMENT_PARTS: tuple[tuple[str, int, int], ...] = (
    ("head", 9, 10), ("neck", 8, 9),
    ("left_upper_arm", 11, 12), ("left_forearm", 12, 13),
    ("right_upper_arm", 14, 15), ("right_forearm", 15, 16),
    ("right_thigh", 1, 2), ("right_shin", 2, 3),
    ("left_thigh", 4, 5), ("left_shin", 5, 6),
)
TORSO_JOINTS = (0, 1, 4, 7, 8, 11, 14)
# Segments whose union is the torso's shape (for its prior mask): spine, hips, shoulders, both sides.
TORSO_SEGMENTS = ((0, 8), (1, 4), (11, 14), (1, 11), (4, 14))
# Part radii as a fraction of the target's torso length (pelvis -> thorax): a part's prior mask wins over the
# background within this distance of its segment(s); limb segments are extended past their end joint by
# PART_EXTEND of their length (hands past the wrist, feet past the ankle, the skull past the head joint).
PART_RADIUS = {"torso": 0.25, "head": 0.34, "neck": 0.25, "left_upper_arm": 0.24, "right_upper_arm": 0.24,
               "left_forearm": 0.2, "right_forearm": 0.2, "left_thigh": 0.34, "right_thigh": 0.34,
               "left_shin": 0.26, "right_shin": 0.26}
PART_EXTEND = {"head": 0.25, "left_forearm": 0.35, "right_forearm": 0.35, "left_shin": 0.12, "right_shin": 0.12}
NUM_PARTS = 1 + len(SEGMENT_PARTS)  # torso + limbs
NUM_COMPONENTS = NUM_PARTS + 1  # + background
BACKGROUND_LOGIT = -2.0  # -0.5 (d / sigma)^2 with sigma = radius / 2 equals this at d = radius
MASK_SHARPNESS = 3.0
CROP_MARGIN = 0.25  # the crop is the two poses' box grown by this fraction of its side
PLATE_GROW = 0.08  # the person region removed from the background plate is grown by this x torso length
SAMPLE_MODES = ("bilinear", "bicubic")
FLOW_UNIT = 1.0 / 32.0  # the flow residual's unit, as a fraction of the image side


@dataclass(frozen=True)
class WarpGeneratorConfig:
    """Architecture of the warping generator.

    Attributes:
        domain: ``"body"`` (the only domain: the parts are H36M-17 limbs).
        image_size: the model's square size (crops are resized to it); a multiple of 2**(levels - 1).
        structure_channels: channels of the target structure map (17 heatmaps + 16 limb maps).
        channels: unused (kept for configs written before the quarter-resolution design).
        motion_channels: channels per level of the network (level 0 at 1 / net_scale of the resolution):
            it corrects the part masks and predicts visibility and an inpainting; the warped reference is
            composited at full resolution.
        net_scale: the network's level 0 works at 1 / net_scale of the image size (2 or 4).
        flow_correction: the network also predicts a dense residual of the person's flow (2 channels, in
            units of image_size / 32 pixels, zero at initialisation), added to the mask-weighted part flow:
            it moves what the rigid part transforms put a few pixels off (loose clothing, a limb turning
            out of the image plane).
        sample_mode: how the reference is sampled by the final flow, ``"bilinear"`` or ``"bicubic"``
            (sharper: bilinear sampling at sub-pixel offsets low-passes the texture it moves).
    """

    domain: str = "body"
    image_size: int = 128
    structure_channels: int = 33
    channels: tuple[int, ...] = (16, 32, 64)
    motion_channels: tuple[int, ...] = (16, 32, 64)
    net_scale: int = 4
    flow_correction: bool = False
    sample_mode: str = "bilinear"

    def __post_init__(self) -> None:
        if self.domain != "body":
            raise ValueError(f"the warp generator makes body frames only, got domain {self.domain!r}")
        for name, ch in (("channels", self.channels), ("motion_channels", self.motion_channels)):
            if len(ch) < 2:
                raise ValueError(f"{name} needs at least two levels")
        if self.net_scale not in (1, 2, 4):
            raise ValueError(f"net_scale must be 1, 2 or 4, got {self.net_scale}")
        if self.sample_mode not in SAMPLE_MODES:
            raise ValueError(f"sample_mode must be one of {SAMPLE_MODES}, got {self.sample_mode!r}")
        factor = self.net_scale * 2 ** (len(self.motion_channels) - 1)
        if self.image_size < factor or self.image_size % factor:
            raise ValueError(f"image_size {self.image_size} must be a positive multiple of {factor}")

    def to_json(self) -> str:
        return json.dumps(dataclasses.asdict(self), sort_keys=True)

    @classmethod
    def from_dict(cls, values: dict) -> "WarpGeneratorConfig":
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = set(values) - known
        if unknown:
            raise ValueError(f"WarpGeneratorConfig has no field(s) {sorted(unknown)}")
        values = dict(values)
        for key in ("channels", "motion_channels"):
            if key in values:
                values[key] = tuple(int(c) for c in values[key])
        return cls(**values)


# --- the analytic part of the motion field ----------------------------------------------------------------

def _perp(v: torch.Tensor) -> torch.Tensor:
    """Rotate (..., 2) vectors by +90 degrees."""
    return torch.stack([-v[..., 1], v[..., 0]], dim=-1)


def torso_similarity(ref: torch.Tensor, tgt: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Least-squares similarity (scale, rotation, shift) taking the target torso joints to the reference's.

    Args:
        ref, tgt: (B, 17, 2) joints.
    Returns:
        scale (B,), rotation (B, 2, 2), shift (B, 2) with ``ref ~ scale * R @ tgt + shift``.
    """
    idx = list(TORSO_JOINTS)
    p, q = ref[:, idx], tgt[:, idx]  # (B, J, 2)
    mp, mq = p.mean(1, keepdim=True), q.mean(1, keepdim=True)
    pc, qc = p - mp, q - mq
    dot = (qc * pc).sum((1, 2))
    cross = (qc[..., 0] * pc[..., 1] - qc[..., 1] * pc[..., 0]).sum(1)
    norm = (qc**2).sum((1, 2)).clamp_min(1e-6)
    scale = (torch.sqrt(dot**2 + cross**2) / norm).clamp(0.2, 5.0)
    angle = torch.atan2(cross, dot)
    c, s = torch.cos(angle), torch.sin(angle)
    rot = torch.stack([torch.stack([c, -s], -1), torch.stack([s, c], -1)], -2)  # (B, 2, 2)
    shift = mp[:, 0] - scale[:, None] * torch.einsum("bij,bj->bi", rot, mq[:, 0])
    return scale, rot, shift


def _segment_distance(pix: torch.Tensor, a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Distance from pixels (H, W, 2) to segments a-b (B, 2) -> (B, H, W)."""
    ab = (b - a)[:, None, None]  # (B, 1, 1, 2)
    ap = pix[None] - a[:, None, None]  # (B, H, W, 2)
    t = ((ap * ab).sum(-1) / (ab**2).sum(-1).clamp_min(1e-6)).clamp(0.0, 1.0)
    return (ap - t[..., None] * ab).norm(dim=-1)


def pixel_centres(height: int, width: int, *, device=None, dtype=torch.float32) -> torch.Tensor:
    """(H, W, 2) pixel-centre coordinates (x, y) = (j + 0.5, i + 0.5)."""
    ys = torch.arange(height, device=device, dtype=dtype) + 0.5
    xs = torch.arange(width, device=device, dtype=dtype) + 0.5
    yy, xx = torch.meshgrid(ys, xs, indexing="ij")
    return torch.stack([xx, yy], dim=-1)


def torso_length(points: torch.Tensor) -> torch.Tensor:
    """(B, 17, 2) -> (B,) pelvis-to-thorax distance in pixels (at least 4)."""
    return (points[:, 8] - points[:, 0]).norm(dim=-1).clamp_min(4.0)


def part_logits(points: torch.Tensor, height: int, width: int) -> torch.Tensor:
    """Prior logits of the parts and the background at every pixel of a frame showing ``points``.

    Args:
        points: (B, 17, 2) joints in that frame's pixels.
    Returns:
        (B, NUM_COMPONENTS, H, W): torso, the limbs of :data:`SEGMENT_PARTS`, then the background.
    """
    pix = pixel_centres(height, width, device=points.device, dtype=points.dtype)
    length = torso_length(points)[:, None, None]  # (B, 1, 1)
    logits = []
    dist = torch.stack([_segment_distance(pix, points[:, a], points[:, b]) for a, b in TORSO_SEGMENTS]).amin(0)
    logits.append(-0.5 * (dist / (0.5 * PART_RADIUS["torso"] * length)) ** 2)
    for name, a, b in SEGMENT_PARTS:
        end = points[:, b] + PART_EXTEND.get(name, 0.0) * (points[:, b] - points[:, a])
        d = _segment_distance(pix, points[:, a], end)
        logits.append(-0.5 * (d / (0.5 * PART_RADIUS[name] * length)) ** 2)
    logits.append(torch.full_like(logits[0], BACKGROUND_LOGIT))
    return torch.stack(logits, dim=1)


def part_maps(ref: torch.Tensor, tgt: torch.Tensor, height: int, width: int) -> torch.Tensor:
    """Backward maps of every component: where each target pixel comes from in the reference.

    Args:
        ref, tgt: (B, 17, 2) joints of the reference and target frames (same pixel frame).
    Returns:
        (B, NUM_COMPONENTS, H, W, 2) reference pixel coordinates (torso, limbs, background = identity).
    """
    pix = pixel_centres(height, width, device=ref.device, dtype=ref.dtype)  # (H, W, 2)
    scale, rot, shift = torso_similarity(ref, tgt)
    maps = [torch.einsum("bij,hwj->bhwi", scale[:, None, None] * rot, pix) + shift[:, None, None]]
    for _, a, b in SEGMENT_PARTS:
        ra, rb, ta, tb = ref[:, a], ref[:, b], tgt[:, a], tgt[:, b]
        t_len = (tb - ta).norm(dim=-1).clamp_min(1.0)  # (B,)
        r_len = (rb - ra).norm(dim=-1).clamp_min(1.0)
        u_t = (tb - ta) / t_len[:, None]  # (B, 2)
        u_r = (rb - ra) / r_len[:, None]
        along = (r_len / t_len).clamp(1.0 / 3.0, 3.0)
        rel = pix[None] - ta[:, None, None]  # (B, H, W, 2)
        alpha = (rel * u_t[:, None, None]).sum(-1)  # (B, H, W)
        beta = (rel * _perp(u_t)[:, None, None]).sum(-1)
        out = (ra[:, None, None] + (alpha * along[:, None, None])[..., None] * u_r[:, None, None]
               + (beta * scale[:, None, None])[..., None] * _perp(u_r)[:, None, None])
        maps.append(out)
    maps.append(pix[None].expand(ref.shape[0], -1, -1, -1))
    return torch.stack(maps, dim=1)


def segment_affine(ref: np.ndarray, tgt: np.ndarray, part: str) -> np.ndarray:
    """(B, 2, 3) float64 the affine map from reference pixels to target pixels that a limb part of
    :data:`SEGMENT_PARTS` moves by: the inverse of its motion field (:func:`part_maps`), which stretches along the
    segment by the ratio of its lengths and across it by the torso's scale.

    Args:
        ref, tgt: (B, 17, 2) joints of the reference and target frames (same pixel frame).
        part: the part's name, e.g. ``"head"``.
    """
    (a, b), = [(i, j) for name, i, j in SEGMENT_PARTS if name == part]
    r, t = torch.as_tensor(np.asarray(ref, np.float64)), torch.as_tensor(np.asarray(tgt, np.float64))
    scale, _, _ = torso_similarity(r, t)
    ra, rb, ta, tb = r[:, a], r[:, b], t[:, a], t[:, b]
    t_len = (tb - ta).norm(dim=-1).clamp_min(1.0)
    r_len = (rb - ra).norm(dim=-1).clamp_min(1.0)
    u_t, u_r = (tb - ta) / t_len[:, None], (rb - ra) / r_len[:, None]
    along = (r_len / t_len).clamp(1.0 / 3.0, 3.0)
    # target -> reference is ra + M (x - ta), M = along u_r u_t^T + scale perp(u_r) perp(u_t)^T; its inverse:
    inverse = (torch.einsum("bi,bj->bij", u_t, u_r) / along[:, None, None]
               + torch.einsum("bi,bj->bij", _perp(u_t), _perp(u_r)) / scale[:, None, None])
    shift = ta - torch.einsum("bij,bj->bi", inverse, ra)
    return torch.cat([inverse, shift[:, :, None]], dim=2).numpy()


def to_grid(coords: torch.Tensor, height: int, width: int) -> torch.Tensor:
    """Pixel coordinates (..., 2) -> grid_sample coordinates in [-1, 1] (align_corners=False)."""
    return torch.stack([2.0 * coords[..., 0] / width - 1.0, 2.0 * coords[..., 1] / height - 1.0], dim=-1)


def warp_image(image: torch.Tensor, flow_px: torch.Tensor, mode: str = "bilinear") -> torch.Tensor:
    """Sample ``image`` (B, C, h, w) at reference pixel coordinates ``flow_px`` (B, H, W, 2) given in the
    pixels of a (H, W) frame; features at a coarser level are sampled at the same relative places.
    ``mode``: ``"bilinear"`` or ``"bicubic"`` (``grid_sample``'s interpolation)."""
    h, w = flow_px.shape[1:3]
    grid = to_grid(flow_px, h, w)
    if image.shape[-2:] != (h, w):  # a coarser level: resample the grid to its size
        grid = F.interpolate(grid.permute(0, 3, 1, 2), size=image.shape[-2:], mode="bilinear",
                             align_corners=False).permute(0, 2, 3, 1)
    return F.grid_sample(image, grid, mode=mode, padding_mode="border", align_corners=False)


def background_plate(ref_image: torch.Tensor, ref_points: torch.Tensor,
                     person: torch.Tensor | None = None) -> torch.Tensor:
    """The reference frame with its person removed: the region of the reference pose's prior part masks,
    grown by :data:`PLATE_GROW` x the torso length, filled by OpenCV's Telea inpainting (not learned, no
    gradient).

    Args:
        ref_image: (B, 3, H, W) in [0, 1]; ref_points: (B, 17, 2) pixels.
        person: (B, H, W) the reference person's prior region when already computed.
    Returns:
        (B, 3, H, W) in [0, 1].
    """
    import cv2

    b, _, h, w = ref_image.shape
    with torch.no_grad():
        if person is None:
            person = 1.0 - torch.softmax(MASK_SHARPNESS * part_logits(ref_points, h, w), dim=1)[:, -1]  # (B, H, W)
        grow = (PLATE_GROW * torso_length(ref_points)).round().int().clamp_min(1).tolist()
        images = (ref_image.detach().clamp(0, 1) * 255).round().to(torch.uint8).permute(0, 2, 3, 1).cpu().numpy()
        masks = (person > 0.05).cpu().numpy().astype(np.uint8)
    out = np.empty_like(images)
    for i in range(b):
        kernel = np.ones((2 * grow[i] + 1, 2 * grow[i] + 1), np.uint8)
        out[i] = cv2.inpaint(np.ascontiguousarray(images[i]), cv2.dilate(masks[i], kernel), 3, cv2.INPAINT_TELEA)
    return torch.from_numpy(out).permute(0, 3, 1, 2).to(ref_image.dtype).div(255.0)


def person_flow(masks: torch.Tensor, maps: torch.Tensor, residual: torch.Tensor | None = None) -> torch.Tensor:
    """The person's backward flow: the parts' maps weighted by their masks (normalised over the parts),
    plus the learned ``residual`` (B, H, W, 2) pixels when given.

    Args:
        masks: (B, K, H, W) softmax over the components (background last); maps: (B, K, H, W, 2).
    Returns:
        (B, H, W, 2) reference pixel coordinates.
    """
    person = masks[:, :-1]  # (B, P, H, W)
    weight = person.sum(1)[..., None].clamp_min(1e-4)  # (B, H, W, 1)
    flow = (person[..., None] * maps[:, :-1]).sum(1) / weight
    return flow if residual is None else flow + residual


def composite(ref_image: torch.Tensor, plate: torch.Tensor, masks: torch.Tensor, flow: torch.Tensor,
              mode: str = "bilinear") -> torch.Tensor:
    """The reference person moved by its flow, over the background plate.

    Args:
        ref_image, plate: (B, 3, H, W); masks: (B, K, H, W) softmax over the components (background last);
        flow: (B, H, W, 2) the person's backward flow in reference pixels (:func:`person_flow`); mode: the
        sampling of :func:`warp_image`.
    Returns:
        (B, 3, H, W): the person's mask x the reference sampled by the flow, plus the background mask x the
        plate.
    """
    weight = masks[:, :-1].sum(1, keepdim=True)  # (B, 1, H, W)
    return weight * warp_image(ref_image, flow, mode) + masks[:, -1:] * plate


# --- networks ---------------------------------------------------------------------------------------------

def _conv(cin: int, cout: int, stride: int = 1) -> nn.Sequential:
    return nn.Sequential(nn.Conv2d(cin, cout, 3, stride=stride, padding=1), nn.LeakyReLU(0.2, inplace=True))


class Pyramid(nn.Module):
    """Conv pyramid: forward(x (B, C, H, W)) -> [(B, ch[l], H / 2**l, W / 2**l) for each level l]."""

    def __init__(self, cin: int, channels: tuple[int, ...]) -> None:
        super().__init__()
        levels = [nn.Sequential(_conv(cin, channels[0]), _conv(channels[0], channels[0]))]
        for a, b in zip(channels[:-1], channels[1:]):
            levels.append(nn.Sequential(_conv(a, b, stride=2), _conv(b, b)))
        self.levels = nn.ModuleList(levels)

    def forward(self, x: torch.Tensor) -> list[torch.Tensor]:
        out = []
        for level in self.levels:
            x = level(x)
            out.append(x)
        return out


class UpDecoder(nn.Module):
    """U-Net decoder over a pyramid: forward(feats) -> (B, out_channels, H, W)."""

    def __init__(self, channels: tuple[int, ...], out_channels: int) -> None:
        super().__init__()
        self.ups = nn.ModuleList()
        self.merges = nn.ModuleList()
        for level in range(len(channels) - 2, -1, -1):
            self.ups.append(_conv(channels[level + 1], channels[level]))
            self.merges.append(nn.Sequential(_conv(2 * channels[level], channels[level]),
                                             _conv(channels[level], channels[level])))
        self.head = nn.Conv2d(channels[0], out_channels, 3, padding=1)

    def forward(self, feats: list[torch.Tensor]) -> torch.Tensor:
        x = feats[-1]
        for i, (up, merge) in enumerate(zip(self.ups, self.merges)):
            x = up(F.interpolate(x, scale_factor=2.0, mode="nearest"))
            x = merge(torch.cat([x, feats[-2 - i]], dim=1))
        return self.head(x)


@dataclass
class WarpOutput:
    """What :meth:`WarpGenerator.forward_parts` computes (all (B, ., H, W) unless said).

    Attributes:
        image: the output frame, about [0, 1].
        warped: the reference warped by the flow.
        inpainting: the painted RGB.
        visibility: (B, 1, H, W) weight of ``warped`` in the output.
        masks: (B, NUM_COMPONENTS, H, W) part masks (softmax).
        flow: (B, H, W, 2) the person's backward flow in reference pixels (:func:`person_flow`).
        person: (B, 1, H, W) soft region of the two people (reference and target poses), for pasting.
    """

    image: torch.Tensor
    warped: torch.Tensor
    inpainting: torch.Tensor
    visibility: torch.Tensor
    masks: torch.Tensor
    flow: torch.Tensor
    person: torch.Tensor


@dataclass
class ReferenceState:
    """A reference prepared by :meth:`WarpGenerator.encode_reference`: the full-resolution image and its
    joints. image: (H, W, 3) uint8; points: (17, 2) float32 pixels."""

    image: np.ndarray
    points: np.ndarray


class WarpGenerator(nn.Module):
    """Reference frame + reference joints + target joints -> target frame, by warping the reference.

    forward(ref_image (B, 3, H, W) in [0, 1], ref_points (B, 17, 2), tgt_points (B, 17, 2),
    tgt_structure (B, S, H, W)) -> (B, 3, H, W) about [0, 1].
    """

    kind = "warp"

    def __init__(self, config: WarpGeneratorConfig) -> None:
        super().__init__()
        self.config = config
        k = NUM_COMPONENTS
        ch = config.motion_channels
        self.image_encoder = Pyramid(3, ch)
        self.encoder = Pyramid(3 + 3 + config.structure_channels + k + 1, ch)
        self.fuse = nn.ModuleList([_conv(2 * c, c) for c in ch])
        self.decoder = UpDecoder(ch, k + 1 + 3 + (2 if config.flow_correction else 0))
        nn.init.zeros_(self.decoder.head.weight)
        nn.init.zeros_(self.decoder.head.bias)
        with torch.no_grad():  # start from the prior masks, copying the composite everywhere
            self.decoder.head.bias[k] = 3.0

    def forward_parts(self, ref_image: torch.Tensor, ref_points: torch.Tensor, tgt_points: torch.Tensor,
                      tgt_structure: torch.Tensor) -> WarpOutput:
        b, _, h, w = ref_image.shape
        k = NUM_COMPONENTS
        ref_points, tgt_points = ref_points.to(ref_image.dtype), tgt_points.to(ref_image.dtype)
        maps = part_maps(ref_points, tgt_points, h, w)  # (B, K, H, W, 2)
        prior = MASK_SHARPNESS * part_logits(tgt_points, h, w)  # (B, K, H, W)
        prior_masks = torch.softmax(prior, dim=1)
        ref_person = 1.0 - torch.softmax(MASK_SHARPNESS * part_logits(ref_points, h, w), dim=1)[:, -1:]
        plate = background_plate(ref_image, ref_points, ref_person[:, 0])  # (B, 3, H, W) without the person
        prior_image = composite(ref_image, plate, prior_masks, person_flow(prior_masks, maps))
        x = torch.cat([prior_image, plate], dim=1) * 2.0 - 1.0
        scale = self.config.net_scale
        net_in = torch.cat([x, tgt_structure, prior_masks, ref_person], dim=1)
        net_in = F.avg_pool2d(net_in, scale) if scale > 1 else net_in
        # Reference features at every level, warped by the prior flow (1 / net_scale resolution and coarser).
        prior_flow = (prior_masks[..., None] * maps).sum(1)  # (B, H, W, 2)
        ref_small = F.avg_pool2d(ref_image * 2 - 1, scale) if scale > 1 else ref_image * 2 - 1
        img_feats = [warp_image(f, prior_flow) for f in self.image_encoder(ref_small)]
        feats = [fuse(torch.cat([a, f], dim=1)) for fuse, a, f in zip(self.fuse, self.encoder(net_in), img_feats)]
        out = F.interpolate(self.decoder(feats), size=(h, w), mode="bilinear", align_corners=False)
        masks = torch.softmax(prior + out[:, :k], dim=1)
        residual = None
        if self.config.flow_correction:  # (B, H, W, 2) pixels
            residual = out[:, k + 4:k + 6].permute(0, 2, 3, 1) * (FLOW_UNIT * w)
        flow = person_flow(masks, maps, residual)  # (B, H, W, 2)
        warped = composite(ref_image, plate, masks, flow, self.config.sample_mode)
        visibility = torch.sigmoid(out[:, k:k + 1])
        inpainting = torch.sigmoid(out[:, k + 1:k + 4] + torch.logit(plate.clamp(0.02, 0.98)))
        image = visibility * warped + (1.0 - visibility) * inpainting
        person = torch.maximum(ref_person, 1.0 - masks[:, -1:])
        return WarpOutput(image=image, warped=warped, inpainting=inpainting, visibility=visibility, masks=masks,
                          flow=flow, person=person)

    def forward(self, ref_image: torch.Tensor, ref_points: torch.Tensor, tgt_points: torch.Tensor,
                tgt_structure: torch.Tensor) -> torch.Tensor:
        return self.forward_parts(ref_image, ref_points, tgt_points, tgt_structure).image

    # --- inference on full-resolution frames: one reference, many targets ------------------------------

    def encode_reference(self, ref_image: np.ndarray, ref_keypoints: np.ndarray, *, path=None) -> ReferenceState:
        """Check and hold a reference: (H, W, 3) uint8 image, (17, 2) joints in its pixels; ``path``, the image's
        file, is named in the errors.

        Raises:
            InputError: joints outside the image, or no visible person (joints not finite, all within
                two pixels of each other, or a uniform image along the pose's limbs).
        """
        image = np.asarray(ref_image)
        points = np.asarray(ref_keypoints, np.float64)
        if image.ndim != 3 or image.shape[2] != 3 or image.dtype != np.uint8:
            raise ValueError(f"reference image must be (H, W, 3) uint8, got {image.shape} {image.dtype}")
        if points.shape != (NUM_JOINTS, 2):
            raise ValueError(f"reference keypoints must be (17, 2), got {points.shape}")
        check_reference_points(points, width=image.shape[1], height=image.shape[0], path=path)
        check_reference_person(image, points, path=path)
        return ReferenceState(image=np.ascontiguousarray(image), points=points.astype(np.float32))

    @torch.inference_mode()
    def decode(self, state: ReferenceState, target_keypoints: np.ndarray, *, batch_size: int = 8) -> np.ndarray:
        """Target frames at the reference's resolution.

        One square crop holding the reference pose and every target pose (grown by :data:`CROP_MARGIN`,
        never smaller than the model size when the image allows) is resized to the model size, generated,
        resized back and pasted into the reference with a soft mask around the two people.

        Args:
            state: from :meth:`encode_reference`.
            target_keypoints: (17, 2) or (T, 17, 2) joints in the reference image's pixels.
        Returns:
            (T, H, W, 3) uint8 frames ((1, H, W, 3) for one pose).
        Raises:
            InputError: the crop would be empty (the poses lie outside the image).
        """
        import cv2

        from motion2video.generator.data import body_structures

        targets = np.asarray(target_keypoints, np.float64).reshape(-1, NUM_JOINTS, 2)
        if not np.all(np.isfinite(targets)):
            raise InputError("target keypoints are not finite")
        height, width = state.image.shape[:2]
        x0, y0, side = person_crop(state.points, targets, width=width, height=height,
                                   model_size=self.config.image_size)
        size = self.config.image_size
        scale = size / side
        crop = state.image[y0:y0 + side, x0:x0 + side]
        crop_small = crop if side == size else cv2.resize(crop, (size, size), interpolation=cv2.INTER_AREA)
        ref_pts = (state.points - [x0, y0]) * scale  # (17, 2)
        tgt_pts = (targets - [x0, y0]) * scale  # (T, 17, 2)
        self.eval()
        out = np.repeat(state.image[None], len(targets), axis=0)
        x_ref = torch.from_numpy(np.ascontiguousarray(crop_small)).permute(2, 0, 1)[None].float() / 255.0
        for start in range(0, len(targets), batch_size):
            t = torch.from_numpy(tgt_pts[start:start + batch_size]).float()  # (b, 17, 2)
            n = t.shape[0]
            structure = torch.from_numpy(body_structures(t.numpy(), size))
            parts = self.forward_parts(x_ref.expand(n, -1, -1, -1), torch.from_numpy(ref_pts).float()[None]
                                       .expand(n, -1, -1), t, structure)
            gen = parts.image.clamp(0, 1).permute(0, 2, 3, 1).numpy()  # (b, s, s, 3)
            alpha = paste_mask(parts.person[:, 0].numpy(), size)  # (b, s, s)
            paste_generated(out[start:start + n], crop, (x0, y0, side), gen, alpha)
        return out


def paste_generated(frames: np.ndarray, crop: np.ndarray, box: tuple[int, int, int], generated: np.ndarray,
                    alpha: np.ndarray) -> None:
    """Paste person crops generated at the model's size back into full-resolution frames, in place.

    Args:
        frames: (n, H, W, 3) uint8 frames to write into (copies of the reference).
        crop: (side, side, 3) uint8 the reference's crop, the base the generated person is blended over.
        box: (x0, y0, side) of the crop in the frames.
        generated: (n, s, s, 3) float frames in about [0, 1] at the model's size s.
        alpha: (n, s, s) paste masks (:func:`paste_mask`).
    """
    import cv2

    x0, y0, side = box
    size = generated.shape[1]
    base = crop.astype(np.float32) / 255.0
    for k in range(len(generated)):
        g, a = generated[k], alpha[k]
        if side != size:
            g = cv2.resize(g, (side, side), interpolation=cv2.INTER_CUBIC)
            a = cv2.resize(a, (side, side), interpolation=cv2.INTER_LINEAR)
        mixed = a[..., None] * np.clip(g, 0, 1) + (1.0 - a[..., None]) * base
        frames[k, y0:y0 + side, x0:x0 + side] = np.clip(np.rint(mixed * 255.0), 0, 255)


def paste_mask(person: np.ndarray, size: int) -> np.ndarray:
    """Soft paste mask from the two people's soft region (B, s, s) in [0, 1]: grown (max filter of about
    4 % of the crop) and feathered (Gaussian), so the seam lies on unchanged background."""
    import cv2

    grow = max(3, int(round(0.04 * size)) | 1)
    kernel = np.ones((grow, grow), np.uint8)
    out = []
    for p in person:
        m = cv2.dilate((p > 0.05).astype(np.uint8), kernel).astype(np.float32)
        out.append(cv2.GaussianBlur(m, (0, 0), sigmaX=max(1.0, size / 128.0)))
    return np.clip(np.stack(out), 0.0, 1.0)


def check_reference_points(points: np.ndarray, *, width: int, height: int, path=None) -> None:
    """Raise InputError (naming ``path`` when given) when reference joints (17, 2) leave the image or show
    no person."""
    points = np.asarray(points, np.float64)
    if not np.all(np.isfinite(points)):
        raise InputError("the reference pose has joints that are not finite (no visible person)", path)
    outside = (points[:, 0] < 0) | (points[:, 0] > width) | (points[:, 1] < 0) | (points[:, 1] > height)
    if np.any(outside):
        raise InputError(f"the reference pose has {int(outside.sum())} joint(s) outside the {width}x{height} "
                         "image", path)
    extent = points.max(0) - points.min(0)
    if float(extent.max()) < 2.0:
        raise InputError("the reference pose shows no visible person (all joints within 2 pixels)", path)


# Below this grey-level spread along the pose's limbs the reference shows nothing there (a uniform
# image or an empty backdrop under the pose): a person, even in clothes of the backdrop's colour, leaves
# edges along the limbs. A uniform fill measures 0; the demo references 72 and 77.
MIN_PERSON_CONTRAST = 4.0


def limb_thickness(points: np.ndarray) -> int:
    """The width :func:`limb_region` draws a limb with, in pixels: about 8 % of the pose's height (joints (17, 2)),
    at least 3."""
    return max(3, int(round(0.08 * float(np.ptp(np.asarray(points, np.float64)[:, 1])))))


def limb_region(points: np.ndarray, *, width: int, height: int, limbs: tuple[int, ...] | None = None) -> np.ndarray:
    """(height, width) bool mask of the pose's limbs drawn as thick lines (:func:`limb_thickness`): where the
    reference person must be, given joints (17, 2) in pixels. ``limbs``: the child joints of the bones to draw
    (None: all 16)."""
    import cv2

    from motion2video.core.skeletons import H36M_17

    pts = np.asarray(points, np.float64)
    thickness = limb_thickness(pts)
    mask = np.zeros((height, width), np.uint8)
    for child, parent in enumerate(H36M_17.parents):
        if parent >= 0 and (limbs is None or child in limbs):
            a, b = np.rint(pts[child]).astype(int), np.rint(pts[parent]).astype(int)
            cv2.line(mask, (int(a[0]), int(a[1])), (int(b[0]), int(b[1])), 1, thickness)
    return mask.astype(bool)


def check_reference_person(image: np.ndarray, points: np.ndarray, path=None) -> None:
    """InputError (naming ``path``) when the image (H, W, 3) uint8 shows nothing along the limbs of the pose
    ``points`` (17, 2), already checked by :func:`check_reference_points` (grey-level standard deviation there
    below :data:`MIN_PERSON_CONTRAST`): a blank or uniform reference has no person to move."""
    height, width = image.shape[:2]
    region = limb_region(points, width=width, height=height)
    grey = np.asarray(image, np.float64).mean(axis=2)
    if not region.any() or float(grey[region].std()) < MIN_PERSON_CONTRAST:
        raise InputError("the reference image shows no visible person where its pose is (the image is uniform "
                         "along the pose's limbs)", path)


def person_crop(ref_points: np.ndarray, tgt_points: np.ndarray, *, width: int, height: int,
                model_size: int) -> tuple[int, int, int]:
    """The square crop (x0, y0, side) holding the reference joints (17, 2) and target joints (T, 17, 2),
    grown by :data:`CROP_MARGIN`, at least ``model_size`` (when the image allows), inside the image.

    Raises:
        InputError: the target poses' box does not meet the image (the crop would be empty).
    """
    tgt = np.asarray(tgt_points, np.float64).reshape(-1, 2)
    t_lo, t_hi = tgt.min(0), tgt.max(0)
    if t_hi[0] <= 0 or t_hi[1] <= 0 or t_lo[0] >= width or t_lo[1] >= height:
        raise InputError("the person crop is empty: the target poses lie outside the reference image")
    pts = np.concatenate([np.asarray(ref_points, np.float64).reshape(-1, 2), tgt])
    lo, hi = np.maximum(pts.min(0), 0), np.minimum(pts.max(0), [width, height])
    side = int(np.ceil(max(hi - lo) * (1.0 + CROP_MARGIN)))
    side = min(max(side, model_size, 8), width, height)
    centre = 0.5 * (lo + hi)
    x0 = int(np.clip(round(centre[0] - side / 2), 0, width - side))
    y0 = int(np.clip(round(centre[1] - side / 2), 0, height - side))
    return x0, y0, side


def warp_generate(model: WarpGenerator, ref_images: np.ndarray, ref_points: np.ndarray,
                  tgt_points: np.ndarray) -> np.ndarray:
    """Generate each pair's target frame through the inference path (crop, generate, paste).

    Args:
        ref_images: (N, H, W, 3) uint8; ref_points, tgt_points: (N, 17, 2) pixels.
    Returns:
        (N, H, W, 3) uint8.
    """
    out = np.empty_like(ref_images)
    for i, (img, p, q) in enumerate(zip(ref_images, ref_points, tgt_points)):
        # Evaluation references come from renders, whose joints may leave the frame: clip them for the
        # check, the generator itself takes them as they are.
        state = ReferenceState(image=np.ascontiguousarray(img), points=np.asarray(p, np.float32))
        out[i] = model.decode(state, q)[0]
    return out
