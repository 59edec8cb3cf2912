"""A body frame generator that moves the reference person through a body mesh.

The keypoint warp (:mod:`motion2video.generator.warp`) guesses a dense flow from 2D joints: per-limb rigid
transforms blended by soft part masks. 2D joints carry neither limb twist nor which side of a limb faces the
camera, so moved limbs tear and blur. Here the flow comes from the correspondence of one body mesh rendered in
the reference pose and in the target pose (:mod:`motion2video.generator.mesh_flow`), as in Liquid Warping GAN
(Liu et al., ICCV 2019) and Dense Pose Transfer (Neverova et al., ECCV 2018):

1. *Background.* The reference person's silhouette (grown by :data:`PLATE_GROW_PX`) is removed from the
   reference and filled by OpenCV's Telea inpainting: the plate every target frame is composited over in training.
   On a real picture (``synthesize``, the reconstruction protocol) the plate is the picture with its segmented
   person inpainted at the output's resolution, and the person (:attr:`MeshWarpOutput.person`) is laid over it
   through a soft matte of ``alpha`` (:mod:`motion2video.generator.background`).
2. *Prior.* Inside the target silhouette the reference is sampled along the mesh flow; the mesh's visibility
   map says where the reference shows that surface point. The reference person is sampled with the background
   outside it given the nearest person colour (:func:`fill_outside_person`, :func:`person_edge_refined`), so a
   sample near the person's outline never takes the background's colour.
3. *Network.* A small U-Net sees the prior frame, the plate, the target's joint heatmaps, silhouette and
   visibility, and the reference's encoder features warped along the flow at every scale. It predicts
   corrections (all zero at initialisation, so the untrained model is the prior): the person's alpha (hair
   and clothes the mesh does not have), the visibility, a flow residual, and an inpainting for what the
   reference does not show (the back of the head, the hidden side of a limb), painted as a change to the
   warped colour.

Output = ``alpha * (v * warped + (1 - v) * inpainting) + (1 - alpha) * plate``.

Images in the network are float (B, 3, H, W) in [0, 1]; flows are (B, H, W, 2) reference pixel coordinates
(x right, y down, pixel centres at integer + 0.5).
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

from motion2video.generator.warp import FLOW_UNIT, SAMPLE_MODES, Pyramid, UpDecoder, _conv, warp_image

PLATE_GROW_PX = 3  # the reference silhouette is grown by this many pixels (at 128 px) before inpainting
ALPHA_PRIOR = 4.0  # logit of the person's alpha from the target silhouette: +-this
VISIBILITY_PRIOR = 3.0  # logit of the visibility from the mesh's visibility map: (2 v - 1) x this
OUT_CHANNELS = 7  # alpha, visibility, inpainting RGB, flow residual (x, y)
HEAD_ZONE = 1.5  # head_cut: the head zone's side, times the thorax-to-head distance


@dataclass(frozen=True)
class MeshWarpConfig:
    """Architecture of the mesh generator.

    Attributes:
        domain: ``"body"`` (the mesh is Anny's body) or ``"face"`` (the head sub-mesh of the face renderer).
        image_size: the model's square size; a multiple of net_scale * 2**(levels - 1).
        structure_channels: channels of the target's structure map (body: 17 joint heatmaps + 16 limb maps;
            face: 1, the grey render).
        channels: feature channels per network level (level 0 at 1 / net_scale of the image size).
        net_scale: the network's level 0 works at 1 / net_scale of the image size (1, 2 or 4); the warp and the
            composite are at full resolution. A 128 px model at net_scale 2 and a 256 px model at net_scale 4
            have the same weights: the network sees the body at the same scale.
        sample_mode: how the reference is sampled along the flow, ``"bilinear"`` or ``"bicubic"``.
        sharpen: the reference is sampled after an unsharp mask of this amount (:func:`unsharp`; 0 = off):
            resampling at sub-pixel positions and magnification soften the person, and the network, working at
            1 / net_scale of the resolution, cannot put the finest detail back. Bicubic sampling of the
            sharpened reference acts as a sharper interpolation kernel.
    """

    domain: str = "body"
    image_size: int = 128
    structure_channels: int = 33
    channels: tuple[int, ...] = (16, 32, 64, 96)
    net_scale: int = 2
    sample_mode: str = "bicubic"
    sharpen: float = 0.0

    def __post_init__(self) -> None:
        if self.domain not in ("body", "face"):
            raise ValueError(f"the mesh generator makes body or face frames, got domain {self.domain!r}")
        if len(self.channels) < 2:
            raise ValueError("channels needs at least two levels")
        if self.net_scale not in (1, 2, 4):
            raise ValueError(f"net_scale must be 1, 2 or 4, got {self.net_scale}")
        if not 0.0 <= self.sharpen <= 2.0:
            raise ValueError(f"sharpen must be in [0, 2], got {self.sharpen}")
        if self.sample_mode not in SAMPLE_MODES:
            raise ValueError(f"sample_mode must be one of {SAMPLE_MODES}, got {self.sample_mode!r}")
        factor = self.net_scale * 2 ** (len(self.channels) - 1)
        if self.image_size < factor or self.image_size % factor:
            raise ValueError(f"image_size {self.image_size} must be a positive multiple of {factor}")

    def to_json(self) -> str:
        return json.dumps(dataclasses.asdict(self), sort_keys=True)

    @classmethod
    def from_dict(cls, values: dict) -> "MeshWarpConfig":
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = set(values) - known
        if unknown:
            raise ValueError(f"MeshWarpConfig has no field(s) {sorted(unknown)}")
        values = dict(values)
        if "channels" in values:
            values["channels"] = tuple(int(c) for c in values["channels"])
        return cls(**values)


def mesh_plate(ref_image: torch.Tensor, ref_mask: torch.Tensor) -> torch.Tensor:
    """The reference frame with its person removed: the silhouette grown by :data:`PLATE_GROW_PX` (scaled
    with the image size), filled by OpenCV's Telea inpainting (not learned, no gradient).

    Args:
        ref_image: (B, 3, H, W) in [0, 1]; ref_mask: (B, 1, H, W) or (B, H, W) person silhouette in [0, 1].
    Returns:
        (B, 3, H, W) in [0, 1].
    """
    import cv2

    b, _, h, w = ref_image.shape
    grow = max(1, round(PLATE_GROW_PX * w / 128))
    kernel = np.ones((2 * grow + 1, 2 * grow + 1), np.uint8)
    with torch.no_grad():
        images = (ref_image.detach().clamp(0, 1) * 255).round().to(torch.uint8).permute(0, 2, 3, 1).cpu().numpy()
        masks = (ref_mask.detach().reshape(b, h, w) > 0.5).cpu().numpy().astype(np.uint8)
    out = np.empty_like(images)
    for i in range(b):
        out[i] = cv2.inpaint(np.ascontiguousarray(images[i]), cv2.dilate(masks[i], kernel), 3, cv2.INPAINT_TELEA)
    return torch.from_numpy(out).permute(0, 3, 1, 2).to(ref_image.dtype).div(255.0)


def fill_outside_person(image: torch.Tensor, person: torch.Tensor, core_px: int = 0) -> torch.Tensor:
    """The image with every pixel outside the person given the colour of the nearest person pixel (SciPy's
    Euclidean distance transform): what the person's colours are sampled from.

    The flow of a surface point the reference shows only at a grazing angle, or not at all (the completed
    hidden side of a limb, :func:`motion2video.generator.mesh_flow.complete_reference_uv`), lands on the person's
    outline, where bicubic sampling reached the background: white specks along turned legs and around a hand
    that passes a thigh, which the network's inpainting (a change to the sampled colour) kept. With the outside
    filled, a sample near the outline takes the person's colour. Measured alone on the real-mocap pairs of
    ``evaluate-frames --poses`` (exact meshes, frames-body-mesh-256): person PSNR +0.005 / +0.04 / +0.02 dB on
    cmu/08_01, 13_42, 05_14, sharpness -0.01 (docs/results.md, "How the mesh generator colours a fitted body").

    With ``core_px`` > 0 the fill takes the colour of the nearest pixel of the person eroded by that many pixels
    (the person as it is where the erosion leaves nothing): the segmented outline of a real photo runs through
    pixels mixed with the background (the grey between a skier's black trousers and the snow), and spread outward
    those gave a turned leg's samples grey and lilac patches. The person's own pixels are never changed.

    Args:
        image: (B, 3, H, W); person: (B, 1, H, W) or (B, H, W) in [0, 1] (> 0.5 is the person).
        core_px: erosion (pixels) of the person whose colours fill the outside.
    Returns:
        (B, 3, H, W), unchanged on the person (and for an image with no person pixel or no other pixel).
    """
    from scipy.ndimage import binary_erosion, distance_transform_edt

    b, _, h, w = image.shape
    masks = (person.detach().reshape(b, h, w) > 0.5).cpu().numpy()
    out = image.clone()
    for i in range(b):
        if i > 0 and np.array_equal(masks[i], masks[0]) and torch.equal(image[i], image[0]):
            out[i] = out[0]  # one reference expanded over a batch of targets
            continue
        if not masks[i].any() or masks[i].all():
            continue
        core = binary_erosion(masks[i], iterations=core_px) if core_px > 0 else masks[i]
        if not core.any():
            core = masks[i]
        _, (iy, ix) = distance_transform_edt(~core, return_indices=True)
        filled = image[i][:, torch.from_numpy(iy), torch.from_numpy(ix)]
        out[i] = torch.where(torch.from_numpy(masks[i]), image[i], filled)
    return out


# The person whose colours are sampled (:func:`person_edge_refined`): pixels of the mask's outer ring this wide (at
# 128 px) whose colour is within EDGE_TEST_DIFF (any channel, [0, 1]) of the background plate are background.
EDGE_TEST_PX = 1
EDGE_TEST_DIFF = 0.1
# A segmented person (BlazePose's mask of a real picture): the outside takes the colour found this far (at 128 px)
# inside its outline (fill_outside_person's core_px; segmented_core_px). A rendered silhouette's outline is exact and
# keeps the fill from the outline itself.
FILL_CORE_PX = 1.0


def person_edge_refined(image: torch.Tensor, person: torch.Tensor, plate: torch.Tensor, ring_px: float = EDGE_TEST_PX,
                        diff: float = EDGE_TEST_DIFF) -> torch.Tensor:
    """The person mask without the pixels of its outer ring whose colour is the background's.

    A fitted body's silhouette reaches a pixel or so past the pictured person (22% of the outline pixels of the
    demo's reference are its white background), and bicubic sampling there mixes the background in: white patches
    at the back of a turned head and along a hand. Only the ring is tested: a white shirt print inside the person
    stays person.

    Args:
        image: (B, 3, H, W) the reference in [0, 1]; person: (B, 1, H, W) or (B, H, W) in [0, 1]; plate: (B, 3, H, W)
            the background (:func:`mesh_plate`); ring_px: the ring's width at 128 px (scaled with W); diff: the
            largest channel difference to the plate that counts as background.
    Returns:
        (B, 1, H, W) float mask in {0, 1}.
    """
    b, _, h, w = image.shape
    m = (person.reshape(b, 1, h, w) > 0.5).to(image.dtype)
    r = max(1, round(ring_px * w / 128))
    inner = -F.max_pool2d(-m, 2 * r + 1, stride=1, padding=r)  # erosion by r
    like_background = ((image - plate).abs().amax(dim=1, keepdim=True) < diff).to(image.dtype)
    return m * (1.0 - (m - inner) * like_background)


def segmented_core_px(width: int) -> int:
    """The ``core_px`` of :func:`person_colours` for a segmented person in an image ``width`` pixels wide
    (:data:`FILL_CORE_PX` scaled from 128 px)."""
    return max(0, round(FILL_CORE_PX * width / 128))


def person_colours(image: torch.Tensor, person: torch.Tensor, plate: torch.Tensor, *, core_px: int = 0
                   ) -> torch.Tensor:
    """(B, 3, H, W): what the generator samples the person's colours from: ``image`` with everything outside the
    person (its outline refined against the ``plate``, :func:`person_edge_refined`) given the nearest person colour
    ``core_px`` inside the outline (:func:`fill_outside_person`; :func:`segmented_core_px` for a segmented person,
    0 for a rendered silhouette)."""
    return fill_outside_person(image, person_edge_refined(image, person, plate), core_px=core_px)


def sampled_colours(image: torch.Tensor, ref_mask: torch.Tensor, plate: torch.Tensor,
                    source_mask: torch.Tensor | None = None) -> torch.Tensor:
    """(B, 3, H, W): the reference colours the mesh generator samples: :func:`person_colours` of ``source_mask``, a
    segmented person, filled from inside its outline (:func:`segmented_core_px`), or, when None, of the rendered
    silhouette ``ref_mask``, filled from its outline."""
    if source_mask is None:
        return person_colours(image, ref_mask, plate)
    return person_colours(image, source_mask, plate, core_px=segmented_core_px(image.shape[-1]))


UNSHARP_SIGMA_PX = 0.8  # the unsharp mask's Gaussian, pixels (at any image size: it targets resampling blur)


def unsharp(image: torch.Tensor, amount: float, sigma: float = UNSHARP_SIGMA_PX) -> torch.Tensor:
    """``image + amount * (image - gaussian(image, sigma))``, (B, C, H, W), separable 5-tap Gaussian with
    replicated borders; not clamped (the sampled colours are clamped by the composite's consumers)."""
    if amount == 0:
        return image
    radius = 2
    t = torch.arange(-radius, radius + 1, dtype=image.dtype, device=image.device)
    k = torch.exp(-t ** 2 / (2.0 * sigma ** 2))
    k = k / k.sum()
    c = image.shape[1]
    blur = F.conv2d(F.pad(image, (radius, radius, 0, 0), mode="replicate"), k.view(1, 1, 1, -1).expand(c, 1, 1, -1),
                    groups=c)
    blur = F.conv2d(F.pad(blur, (0, 0, radius, radius), mode="replicate"), k.view(1, 1, -1, 1).expand(c, 1, -1, 1),
                    groups=c)
    return image + amount * (image - blur)


def cut_alpha(alpha: torch.Tensor, cut: torch.Tensor, flow: torch.Tensor) -> torch.Tensor:
    """(B, 1, H, W) ``alpha`` times ``cut`` (B, 1, H, W), a reference mask (:func:`head_cut`), sampled along ``flow``
    (B, H, W, 2): a target pixel whose colour comes from where the cut is 0 is background."""
    return alpha * warp_image(cut, flow).clamp(0.0, 1.0)


def head_cut(person: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(S, S) float32: 0 where the reference's head zone is not the person, 1 elsewhere. The zone is the square of
    :data:`HEAD_ZONE` times the thorax-to-head distance around the middle of the neck and head joints
    (:func:`motion2video.generator.head_paste.head_squares`).

    A body fitted to a real person is not their outline: its silhouette, grown by the clothes margin
    (:func:`motion2video.generator.mesh_reference.clothes_margin`), reaches past a slim person's head, and there the
    flow lands on the reference's background, which :func:`fill_outside_person` paints with the nearest person
    colour. The network, trained on renders whose person is the mesh's silhouette, keeps those pixels as person: on
    ``dancer.avi`` a halo of face and hair colours stood around the head, like a second head beside it. Cut there
    (:func:`cut_alpha`), the head is the pictured one. Along the limbs the same cut opened holes of background in
    thin legs whose fitted mesh lies a little beside them (docs/experiments.md), so it is kept to the head.

    Args:
        person: (S, S) the reference's segmented person in [0, 1]; points: (17, 2) its joints in the same pixels.
    """
    from motion2video.generator.head_paste import head_squares

    zone = head_squares(np.asarray(points)[None], person.shape[0], scale=HEAD_ZONE, min_side=HEAD_ZONE)[0]
    return np.where(zone, np.asarray(person, np.float32), 1.0).astype(np.float32)


@dataclass
class MeshWarpOutput:
    """What :meth:`MeshWarpGenerator.forward_parts` computes (all (B, ., H, W) unless said).

    Attributes:
        image: the output frame, about [0, 1].
        warped: the reference sampled along the final flow.
        inpainting: the painted RGB of the person.
        visibility: (B, 1, H, W) weight of ``warped`` inside the person.
        alpha: (B, 1, H, W) the person's coverage.
        flow: (B, H, W, 2) the final backward flow, reference pixels.
        plate: (B, 3, H, W) the background without the reference person.
        person: (B, 3, H, W) the person's colours, ``visibility * warped + (1 - visibility) * inpainting`` (what
            ``image`` lays over the plate through ``alpha``; :func:`motion2video.generator.background.composite` lays
            it over a full-resolution background).
    """

    image: torch.Tensor
    warped: torch.Tensor
    inpainting: torch.Tensor
    visibility: torch.Tensor
    alpha: torch.Tensor
    flow: torch.Tensor
    plate: torch.Tensor
    person: torch.Tensor


class MeshWarpGenerator(nn.Module):
    """Reference frame + mesh correspondence -> target frame.

    forward(ref_image (B, 3, H, W) in [0, 1], ref_mask (B, 1, H, W), flow (B, H, W, 2), visibility
    (B, 1, H, W), silhouette (B, 1, H, W), tgt_structure (B, S, H, W) (or (B, S, H / net_scale, W / net_scale), the
    maps already averaged over the network's blocks), source_mask=None) -> (B, 3, H, W) about [0, 1]; ``source_mask``
    as in :meth:`forward_parts`.
    """

    kind = "mesh"

    def __init__(self, config: MeshWarpConfig) -> None:
        super().__init__()
        self.config = config
        ch = config.channels
        self.image_encoder = Pyramid(3, ch)
        self.encoder = Pyramid(3 + 3 + config.structure_channels + 3, ch)
        self.fuse = nn.ModuleList([_conv(2 * c, c) for c in ch])
        self.decoder = UpDecoder(ch, OUT_CHANNELS)
        nn.init.zeros_(self.decoder.head.weight)
        nn.init.zeros_(self.decoder.head.bias)

    def forward_parts(self, ref_image: torch.Tensor, ref_mask: torch.Tensor, flow: torch.Tensor,
                      visibility: torch.Tensor, silhouette: torch.Tensor, tgt_structure: torch.Tensor,
                      plate: torch.Tensor | None = None, source_mask: torch.Tensor | None = None,
                      colours: torch.Tensor | None = None, person_cut: torch.Tensor | None = None
                      ) -> MeshWarpOutput:
        """The output and its parts.

        Args: as :meth:`forward`, and plate: (B, 3, H, W) the background (:func:`mesh_plate` of the reference
            when None); source_mask: (B, 1, H, W) the reference pixels that are the person, whose colours are
            sampled (:func:`fill_outside_person`; ``ref_mask`` when None). For a fitted body, the segmented
            person (:func:`mesh_source_mask`, :func:`motion2video.stages.mesh_generation.sampled_person`), whose
            outside is filled from inside its outline (:func:`segmented_core_px`).
            colours: (B, 3, H, W) :func:`sampled_colours` of the reference when the caller has them already (one
            reference for many batches of targets); ``source_mask`` is then not used.
            person_cut: (B, 1, H, W) for a body fitted to a real person, :func:`head_cut` of the reference: the
            alpha is multiplied by it sampled along the final flow (:func:`cut_alpha`). None (rendered pairs,
            training): the alpha as the network gives it.
        """
        b, _, h, w = ref_image.shape
        dtype = ref_image.dtype
        flow, visibility, silhouette = flow.to(dtype), visibility.to(dtype), silhouette.to(dtype)
        if plate is None:
            plate = mesh_plate(ref_image, ref_mask)
        mode = self.config.sample_mode
        # what the person's colours are sampled from
        source = colours if colours is not None else sampled_colours(ref_image, ref_mask, plate, source_mask)
        sampled = unsharp(source, self.config.sharpen)
        prior_person = warp_image(sampled, flow, mode)
        prior = silhouette * prior_person + (1.0 - silhouette) * plate
        scale = self.config.net_scale
        # every input but the structure is pooled together; the structure may come pooled already
        # (generator.data.pooled_body_structures), as it is the input's most channels
        rest = torch.cat([prior * 2.0 - 1.0, plate * 2.0 - 1.0, silhouette, visibility,
                          warp_image(ref_mask.to(dtype), flow)], dim=1)
        ref_in = ref_image * 2.0 - 1.0
        structure = tgt_structure.to(dtype)
        if scale > 1:
            rest, ref_in = F.avg_pool2d(rest, scale), F.avg_pool2d(ref_in, scale)
            if structure.shape[-1] == w:
                structure = F.avg_pool2d(structure, scale)
        net_in = torch.cat([rest[:, :6], structure, rest[:, 6:]], dim=1)
        ref_feats = [warp_image(f, flow) for f in self.image_encoder(ref_in)]
        feats = [fuse(torch.cat([a, r], dim=1)) for fuse, a, r in zip(self.fuse, self.encoder(net_in), ref_feats)]
        out = self.decoder(feats)
        if scale > 1:
            out = F.interpolate(out, size=(h, w), mode="bilinear", align_corners=False)
        alpha = torch.sigmoid(ALPHA_PRIOR * (2.0 * silhouette - 1.0) + out[:, 0:1])
        vis = torch.sigmoid(VISIBILITY_PRIOR * (2.0 * visibility - 1.0) + out[:, 1:2])
        final_flow = flow + out[:, 5:7].permute(0, 2, 3, 1) * (FLOW_UNIT * w)
        warped = warp_image(sampled, final_flow, mode)
        if person_cut is not None:
            alpha = cut_alpha(alpha, person_cut.to(dtype), final_flow)
        inpainting = torch.sigmoid(out[:, 2:5] + torch.logit(warped.clamp(0.02, 0.98)))
        person = vis * warped + (1.0 - vis) * inpainting
        image = alpha * person + (1.0 - alpha) * plate
        return MeshWarpOutput(image=image, warped=warped, inpainting=inpainting, visibility=vis, alpha=alpha,
                              flow=final_flow, plate=plate, person=person)

    def forward(self, ref_image: torch.Tensor, ref_mask: torch.Tensor, flow: torch.Tensor, visibility: torch.Tensor,
                silhouette: torch.Tensor, tgt_structure: torch.Tensor, source_mask: torch.Tensor | None = None
                ) -> torch.Tensor:
        return self.forward_parts(ref_image, ref_mask, flow, visibility, silhouette, tgt_structure,
                                  source_mask=source_mask).image


def mesh_source_mask(pairs) -> torch.Tensor | None:
    """(B, 1, H, W) the reference person whose colours the mesh generator samples, for pairs with fitted meshes:
    the segmented person (BlazePose's mask), not the fitted mesh's silhouette, which reaches past a real person
    where the fit is off; None for pairs whose mesh is exact (the generator then uses the reference's silhouette).

    Why not the segmented person joined with the fitted silhouette grown by the clothes margin: on a real photo that
    lends the snow beside a skier's legs to her trousers (white patches in every frame), and on ``dancer.avi`` the
    person PSNR of ``evaluate-frames --video`` was 20.64 dB with it against 21.19 with the segmented person alone
    (docs/results.md, "How the mesh generator colours a fitted body")."""
    if pairs.mesh_ref_masks is None:
        return None
    return torch.from_numpy(np.asarray(pairs.ref_masks, bool))[:, None].float()


def mesh_inputs(pairs) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
    """The mesh generator's inputs besides the images, from :class:`generator.data.FramePairs` that carry the mesh
    correspondence: ref_mask (B, 1, H, W), flow (B, H, W, 2), visibility (B, 1, H, W), silhouette (B, 1, H, W) (the
    fitted mesh's silhouettes when the pairs carry them, else the person masks)."""
    ref = pairs.ref_masks if pairs.mesh_ref_masks is None else pairs.mesh_ref_masks
    tgt = pairs.tgt_masks if pairs.mesh_tgt_masks is None else pairs.mesh_tgt_masks
    return (torch.from_numpy(np.ascontiguousarray(ref))[:, None].float(), torch.from_numpy(pairs.mesh_flow),
            torch.from_numpy(pairs.mesh_visibility)[:, None], torch.from_numpy(np.ascontiguousarray(tgt))[:, None].float())
