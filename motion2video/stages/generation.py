"""Generate frames: the one path from structures to RGB frames with the keypoint-conditioned frame generator.

:func:`generate_frames` encodes the reference once (:meth:`~motion2video.generator.model.FrameGenerator.encode_reference`)
and decodes every target structure from it (:meth:`~motion2video.generator.model.FrameGenerator.decode`), the same
two methods :func:`motion2video.generator.model.generate` (evaluation) runs per pair; :func:`generate_video_frames`
runs it over the observed frames and every future of :class:`~motion2video.stages.structure.Structures`.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, replace
from typing import Iterator

import numpy as np

from motion2video.stages.reference import Reference
from motion2video.stages.sampling import torch_threads
from motion2video.stages.structure import Structures, structure_maps, structure_previews, timeline_rows

GENERATE_CHUNK = 64  # target structures materialised at once (33 x 128 x 128 float32 = 2.2 MB each)


def is_warp(net) -> bool:
    """Whether ``net`` is the warp generator (:mod:`motion2video.generator.warp`), which takes keypoints and
    frames of any size, rather than the feature-analogy generator, which takes structure maps."""
    return getattr(net, "kind", "analogy") == "warp"


def is_mesh(net) -> bool:
    """Whether ``net`` is the mesh generator (:mod:`motion2video.generator.mesh_warp`), which takes the body mesh's
    correspondence (:mod:`motion2video.stages.mesh_generation`) and frames of any size."""
    return getattr(net, "kind", "analogy") == "mesh"


def mesh_setup(net, reference: Reference, structures: Structures):
    """Body: the :class:`~motion2video.stages.mesh_generation.MeshVideo` of every target row of ``structures``: the
    reference person's Anny body (the reference pose file's phenotype; without one, Anny's weight fitted to the
    person BlazePose segments) in the reference pose and in every target pose; only the reference vertices that land
    on that segmented person count as shown, the fitted head is moved onto the eyes BlazePose finds
    (:func:`~motion2video.generator.mesh_reference.align_face`) and a fitted hand vertex that lands beside the pictured
    hand samples the pictured hand (:func:`~motion2video.generator.mesh_reference.hand_colour_sources`); the face the
    photo shows is found at its own resolution (:func:`~motion2video.stages.pictured_face.reference_face`) to be laid
    over the generated heads. Face: None (the face structures carry their head mesh)."""
    from motion2video.core.errors import InputError
    from motion2video.stages.mesh_generation import mesh_video
    from motion2video.stages.pictured_face import reference_face

    if net.config.domain != structures.domain:
        raise InputError(f"the mesh frame generator makes {net.config.domain} frames, not {structures.domain} frames")
    if structures.domain == "face":
        if structures.face_mesh is None:
            raise InputError("the face mesh generator needs face structures with their head mesh")
        return None
    if structures.placement is None:
        raise InputError("the mesh frame generator makes body frames from a body motion")
    n = structures.num_targets
    phenotype = dict(reference.pose.identity) if reference.pose is not None else {}
    # the person as found where the pose was estimated (in the picture as given, before any pad); else segmented
    # here, where a border the pad or zoom replicated is never the person
    person = reference.person if reference.person is not None else reference_person(reference.image)
    if person is not None:
        person = replace(person, mask=np.where(reference.picture_mask(), person.mask, 0.0).astype(np.float32))
    return mesh_video(structures.placement, structures.points[0], structures.points[1:1 + n], phenotype=phenotype,
                      output_size=structures.size, model_size=net.config.image_size, person=person,
                      image=reference.image, fit_to_mask=not phenotype,
                      pictured=None if reference.pose is None else reference.pose.camera_joints,
                      face=reference_face(reference), from_file=reference.picture_mask(), view=reference.view)


def mesh_frames(net, reference: Reference, structures: Structures, video, rows: np.ndarray, *,
                batch_size: int = 4) -> np.ndarray:
    """(R, S, S, 3) uint8 frames of the mesh generator for target ``rows`` (0 = the first observed frame):
    body through ``video`` (:func:`mesh_setup`), face through the structures' head mesh."""
    from motion2video.stages.mesh_generation import generate_face_mesh_frames, generate_mesh_frames

    if structures.domain == "face":
        return generate_face_mesh_frames(net, reference.image, structures, rows, batch_size=batch_size)
    return generate_mesh_frames(net, reference.image, video, rows, batch_size=batch_size)


def warp_face(reference: Reference, structures: Structures):
    """The keypoint warp's pictured face: the face the reference photo shows, found at its own resolution
    (:func:`~motion2video.stages.pictured_face.reference_face`), moved in each target as the warp moves the head
    (:func:`~motion2video.generator.warp.segment_affine`), laid over as much as the head still shows it
    (:func:`~motion2video.stages.pictured_face.joint_face_moves`). None without a face, for face structures, or for
    a 2D motion model's (which does not say where the head is turned).

    Returns:
        (face, affines (N, 2, 3) output pixels of the reference -> of each target, the
        :class:`~motion2video.generator.head_paste.HeadMoves` of the N targets) or None.
    """
    from motion2video.generator.warp import segment_affine
    from motion2video.stages.pictured_face import joint_face_moves, reference_face

    if structures.domain != "body" or structures.placement is None:
        return None
    face = reference_face(reference)
    if face is None:
        return None
    pictured = None if reference.pose is None else reference.pose.camera_joints
    head = joint_face_moves(face, structures.placement, structures.points[0], pictured=pictured)
    if head is None:
        return None
    targets = structures.points[1:1 + structures.num_targets]
    affines = segment_affine(np.broadcast_to(structures.points[0], targets.shape), targets, "head")
    return face, affines, head


def paste_faces(frames: np.ndarray, targets: np.ndarray, pasted) -> np.ndarray:
    """(R, S, S, 3) uint8 ``frames`` of target indices ``targets`` (R,) (0 = the first observed frame) with the
    pictured face of :func:`warp_face` (``pasted``; None leaves them) laid over each."""
    from motion2video.stages.pictured_face import lay_face

    if pasted is None:
        return frames
    face, affines, head = pasted
    out = np.asarray(frames).copy()
    for i, t in enumerate(np.asarray(targets, np.int64)):
        out[i] = lay_face(out[i], face, head, t, affine=affines[t])
    return out


def warp_skirt(reference: Reference, structures: Structures):
    """The keypoint warp's skirt: cloth the reference shows hanging from the hips across both legs
    (:func:`motion2video.generator.garment.find_skirt`), to be laid over every frame as one panel moved with the hips
    and legs (the warp, like the mesh generators, would split it into two trouser legs). None for face structures,
    or when the reference shows none.

    Returns:
        the :class:`motion2video.generator.garment.Skirt`, or None.
    """
    from motion2video.generator.garment import find_skirt

    if structures.domain != "body":
        return None
    person = reference.person if reference.person is not None else reference_person(reference.image)
    if person is None:
        return None
    cloth = np.where(reference.picture_mask(), person.mask, 0.0).astype(np.float32)
    return find_skirt(reference.image, cloth, structures.points[0])


def skirted(frames: np.ndarray, targets: np.ndarray, structures: Structures, skirt) -> np.ndarray:
    """(R, S, S, 3) uint8 ``frames`` of target indices ``targets`` (R,) (0 = the first observed frame) with the skirt
    of :func:`warp_skirt` (None leaves them) over each, moved with that target's pose."""
    from motion2video.generator.garment import lay_skirts

    if skirt is None:
        return frames
    return lay_skirts(frames, skirt, structures.points[1 + np.asarray(targets, np.int64)])


def reference_person(image: np.ndarray):
    """What BlazePose finds of the person in a reference image (its mask, eyes and hands): a
    :class:`motion2video.stages.reference.ReferencePerson`, or None when it finds nobody."""
    from motion2video.core.errors import InputError
    from motion2video.pose.estimate import default_model, estimate_image
    from motion2video.stages.reference import ReferencePerson

    try:
        pose = estimate_image(image, model=default_model())
    except InputError:  # nobody found
        return None
    return ReferencePerson.of(pose)


def default_generator_threads() -> int:
    """Half the CPU cores, 1 to 4. On the 2-core machines this was built on, two threads were slower than
    one whenever anything else ran (OpenMP threads wait on each other); see ``scripts/bench.py pipeline``. The mesh
    generator keeps one more core busy with its NumPy work
    (:func:`~motion2video.stages.mesh_generation.generate_mesh_frames`)."""
    return max(1, min(4, (os.cpu_count() or 1) // 2))


def generate_frames(model, reference_image: np.ndarray, reference_structure: np.ndarray,
                    target_structures: np.ndarray, *, batch_size: int = 4,
                    channels_last: bool = True) -> np.ndarray:
    """Frames of one reference appearance in many target structures.

    ``decoder(enc_img(x_ref) - enc_pose(p_ref) + enc_pose(p_tgt))`` (+ ``x_ref`` for residual models) through
    :meth:`~motion2video.generator.model.FrameGenerator.encode_reference` and ``decode``: the reference image and
    structure are encoded once, not once per target (the reference is the same for the whole video), under
    ``torch.inference_mode``.

    Args:
        model: a FrameGenerator (or a loaded frame model with ``.model``).
        reference_image: (S, S, 3) uint8.
        reference_structure: (C, S, S) float32.
        target_structures: (N, C, S, S) float32.
        batch_size: targets per forward pass.
        channels_last: run the convolutions in channels-last memory format.
    Returns:
        (N, S, S, 3) uint8.
    """
    import torch

    from motion2video.generator.model import images_to_tensor, tensor_to_images

    net = getattr(model, "model", model)
    cfg = net.config
    size, channels = cfg.image_size, cfg.structure_channels
    if reference_image.shape != (size, size, 3):
        raise ValueError(f"reference_image must be ({size}, {size}, 3), got {reference_image.shape}")
    if reference_structure.shape != (channels, size, size):
        raise ValueError(f"reference_structure must be ({channels}, {size}, {size}), got {reference_structure.shape}")
    if target_structures.ndim != 4 or target_structures.shape[1:] != (channels, size, size):
        raise ValueError(f"target_structures must be (N, {channels}, {size}, {size}), got {target_structures.shape}")
    if batch_size < 1:
        raise ValueError(f"batch_size must be >= 1, got {batch_size}")
    fmt = torch.channels_last if channels_last else torch.contiguous_format
    net.eval()
    net.to(memory_format=fmt)
    out = np.empty((len(target_structures), size, size, 3), np.uint8)
    with torch.inference_mode():
        x_ref = images_to_tensor(reference_image[None]).contiguous(memory_format=fmt)  # (1, 3, S, S)
        p_ref = torch.from_numpy(np.ascontiguousarray(reference_structure[None], np.float32))
        base = net.encode_reference(x_ref, p_ref.contiguous(memory_format=fmt))  # per level (1, C_l, H_l, W_l)
        for start in range(0, len(target_structures), batch_size):
            p_tgt = torch.from_numpy(np.ascontiguousarray(target_structures[start:start + batch_size], np.float32))
            y = net.decode(base, x_ref, p_tgt.contiguous(memory_format=fmt))  # (B, 3, S, S)
            out[start:start + len(p_tgt)] = tensor_to_images(y)
    return out


@dataclass(frozen=True)
class GeneratedFrames:
    """Generated frames. observed: (To, S, S, 3) uint8. futures: (K, Tf, S, S, 3) uint8."""

    observed: np.ndarray
    futures: np.ndarray


def generate_video_frames(model, reference: Reference, structures: Structures, *, batch_size: int = 4,
                          threads: int | None = None, channels_last: bool = True) -> GeneratedFrames:
    """Run :func:`generate_frames` over every observed and future frame of :class:`Structures`, building
    the structure maps a chunk at a time (so a long video never holds all of them). A warp generator
    (:class:`~motion2video.generator.warp.WarpGenerator`) goes through its ``encode_reference`` / ``decode``
    at the structures' size instead (the person generated at the model's size, pasted into the reference)."""
    net = getattr(model, "model", model)
    if is_mesh(net):
        n = structures.num_targets
        with torch_threads(threads):
            video = mesh_setup(net, reference, structures)
            frames = mesh_frames(net, reference, structures, video, np.arange(n), batch_size=batch_size)
        to, k, tf = structures.observed, structures.samples, structures.horizon
        size = structures.size
        return GeneratedFrames(observed=frames[:to], futures=frames[to:].reshape(k, tf, size, size, 3))
    if is_warp(net):
        n = structures.num_targets
        with torch_threads(threads):
            state = net.encode_reference(reference.image, structures.points[0], path=reference.path)
            frames = net.decode(state, structures.points[1:1 + n], batch_size=batch_size)
        frames = skirted(frames, np.arange(n), structures, warp_skirt(reference, structures))
        frames = paste_faces(frames, np.arange(n), warp_face(reference, structures))
        to, k, tf = structures.observed, structures.samples, structures.horizon
        size = structures.size
        return GeneratedFrames(observed=frames[:to], futures=frames[to:].reshape(k, tf, size, size, 3))
    size = net.config.image_size
    if structures.size != size:
        raise ValueError(f"structures are {structures.size} px but the generator makes {size} px frames")
    ref_structure = structure_maps(structures, slice(0, 1))[0]
    n = structures.num_targets
    frames = np.empty((n, size, size, 3), np.uint8)
    with torch_threads(threads):
        for start in range(0, n, GENERATE_CHUNK):
            stop = min(n, start + GENERATE_CHUNK)
            maps = structure_maps(structures, slice(1 + start, 1 + stop))
            frames[start:stop] = generate_frames(net, reference.image, ref_structure, maps, batch_size=batch_size,
                                                 channels_last=channels_last)
    to, k, tf = structures.observed, structures.samples, structures.horizon
    return GeneratedFrames(observed=frames[:to], futures=frames[to:].reshape(k, tf, size, size, 3))


def iter_generated(model, reference: Reference, structures: Structures, *, batch_size: int = 4,
                   threads: int | None = None, channels_last: bool = True, chunk: int = 16,
                   clock: dict | None = None) -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
    """Generate the video time step by time step (all K cells of a step together), a chunk of steps at a
    time, so the grid video can be encoded while it is generated and never held whole.

    Each distinct structure row is generated once (the observed steps are shared by the K cells).
    ``clock["generation"]`` (when given) accumulates the seconds spent generating, the reference's encoding and
    (mesh generator) the fitted meshes of every target included.

    Yields:
        (start, frames, previews): frames (t, K, S, S, 3) uint8 generated for steps start..start+t-1,
        previews the same shape, the structures drawn (:func:`~motion2video.stages.structure.structure_previews`).
    """
    net = getattr(model, "model", model)
    warp = is_warp(net)
    mesh = is_mesh(net)
    t0 = time.perf_counter()
    if mesh:  # the meshes of every target row, once
        with torch_threads(threads):
            video = mesh_setup(net, reference, structures)
    elif warp:  # the warp generator works at any frame size: its person crop is resized to the model's size
        with torch_threads(threads):
            state = net.encode_reference(reference.image, structures.points[0], path=reference.path)
        pasted = warp_face(reference, structures)
        skirt = warp_skirt(reference, structures)
    else:
        size = net.config.image_size
        if structures.size != size:
            raise ValueError(f"structures are {structures.size} px but the generator makes {size} px frames")
        ref_structure = structure_maps(structures, slice(0, 1))[0]
    if clock is not None:  # fitting the reference and the target meshes is part of generating
        clock["generation"] = clock.get("generation", 0.0) + time.perf_counter() - t0
    steps = structures.observed + structures.horizon
    for start in range(0, steps, chunk):
        rows = timeline_rows(structures, start, min(steps, start + chunk))  # (t, K)
        unique, inverse = np.unique(rows, return_inverse=True)
        t0 = time.perf_counter()
        with torch_threads(threads):
            if mesh:
                frames = mesh_frames(net, reference, structures, video, unique - 1, batch_size=batch_size)
            elif warp:
                frames = net.decode(state, structures.points[unique], batch_size=batch_size)
                frames = paste_faces(skirted(frames, unique - 1, structures, skirt), unique - 1, pasted)
            else:
                frames = generate_frames(net, reference.image, ref_structure, structure_maps(structures, unique),
                                         batch_size=batch_size, channels_last=channels_last)
        if clock is not None:
            clock["generation"] = clock.get("generation", 0.0) + time.perf_counter() - t0
        previews = structure_previews(structures, unique)
        shape = rows.shape
        yield start, frames[inverse.reshape(shape)], previews[inverse.reshape(shape)]
