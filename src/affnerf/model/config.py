"""Model configuration: the architecture and how rays are sampled (conventions §4)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from affnerf.objects.asset import CANONICAL_HALF_EXTENT

#: Rays per forward pass when rendering whole images, unless told otherwise: on a CPU about a thousand is fastest
#: (larger chunks spill the caches); on a GPU pass a larger ``--chunk``.
RAYS_PER_CHUNK = 1024
#: Points per forward pass when the field is evaluated at points (occupancy grids, mesh extraction).
POINTS_PER_CHUNK = 65536


@dataclass(frozen=True)
class ModelConfig:
    """Architecture and ray sampling.

    Attributes:
        kind: ``affnerf`` (global shape and appearance codes, conventions §4), ``pixelnerf`` (the PixelNeRF-M
            baseline: pixel-aligned features projected with the input cameras), ``semantic-ray`` (the Semantic-Ray
            baseline: Cross-Reprojection Attention over the posed input views), ``gsnerf`` (the GSNeRF baseline:
            per-view depth from a cost volume, depth-guided rendering; both conventions §4) or ``pose-aware``
            (beyond the paper: AFF-NeRF's codes plus pixel-aligned features at an input camera the model predicts,
            so it needs no pose either; :mod:`affnerf.model.pose_aware`).
        code_dim: size of the shape code and of the appearance code.
        encoder_width: channel multiplier of the two ResNet18 encoders (1.0 = standard ResNet18).
        encoder_resolution: side of the square object crop the encoders see, pixels.
        field_width: hidden width of the field's position trunk.
        field_depth: number of trunk layers.
        color_width: hidden width of the colour head.
        affordance_width: hidden width of the affordance head.
        pe_xyz: positional-encoding frequencies of positions.
        pe_dir: positional-encoding frequencies of view directions.
        num_coarse: stratified samples per ray (coarse field).
        num_fine: hierarchical samples per ray (fine field), added to the coarse ones.
        coarse_field: what places the fine samples: ``own`` (the paper: a second, coarse field, trained with the
            same losses) or ``shared`` (beyond the paper: the fine field itself, evaluated without gradients at the
            stratified samples, as NeuS's hierarchical sampling uses its one network; the model has one field, so
            a training step saves the coarse field's backward pass and its share of the 3D supervision; a
            coarse-only model, ``num_fine`` 0, is trained as usual).
        near: start of every ray, metres.
        far: end of every ray, metres.
        clip_to_cube: sample only where rays cross the scene cube [-scene_half_extent, scene_half_extent]^3 (rays
            that miss it render background without evaluating the field); False samples the whole [near, far] like
            vanilla NeRF.
        scene_half_extent: half the side of the cube the field models, metres: the datasets' canonical cube. Ray
            clipping, occupancy grids and mesh extraction all take it from here.
        surface_density: density (per metre) of the surface that mesh extraction puts at the object's boundary;
            predict, eval and the viewer use this value unless told otherwise. 50/m: a 1 cm slab at this density
            stops about 40 % of the light.
        surface_optical_depth: when > 0, each object's mesh level is lowered below ``surface_density`` to the
            level whose outline along each axis best matches where the field's optical depth along that axis
            exceeds this value (:mod:`affnerf.predict.level`), so an object whose density rises slowly (a large
            or hollow one) is meshed where it renders; 0 uses ``surface_density`` for every object. A departure
            from the paper (which extracts no meshes), chosen with ``surface_density`` by ``affnerf eval
            calibrate``.
        conditioning: how the trunk takes its per-point conditioning (the shape code, or PixelNeRF-M's features):
            ``concat`` joins it to PE(position) at the input and at the skip (the paper), ``film`` also scales and
            shifts every trunk layer's pre-activation by it (FiLM, as Occupancy Networks' CBN decoder); ``triplane``
            (AFF-NeRF only, beyond the paper) decodes the shape code once per object into three axis-aligned
            feature planes over the scene cube, and each point's features read from them join PE(position) and the
            code (:mod:`affnerf.model.triplane`).
        geometry: what the field's density head gives: ``density`` (a softplus of it is the density, the paper) or
            ``sdf`` (beyond the paper: a signed distance whose density is VolSDF's Laplace CDF with a learnt scale,
            :func:`affnerf.model.field.laplace_density`; with 3D supervision it is also trained towards each point's
            truncated distance to the true surface, ``TrainConfig.point_distance_weight``), so free space near a
            thin part or inside a hollow object carries how far the surface is, not only that it is outside; the
            ``small`` preset's field and the shipped model's.
        view_affordance_weight: AFF-NeRF only, beyond the paper: when > 0 its shape encoder also labels the pixels
            of its input crop (a 1x1 convolution over the four stages' features,
            :class:`affnerf.model.resnet.CodeEncoder`), and this weight times that labelling's cross-entropy
            against the crop's true affordance map joins the training loss (``loss/view_affordance``), so the
            encoder is taught to find small parts in the image (a pen's cap, a cabinet's pull), not only the
            object's overall shape. The head serves training only; 0 (the paper): no head.
        projection_camera: ``pose-aware`` only: the camera its query points are projected with to read the image's
            features, ``predicted`` (the camera head's, always: a photo has no pose) or ``given`` (the input view's
            true camera wherever one is given, in training and in a posed evaluation; the predicted one otherwise).
            ``given`` is an oracle, for measuring what pixel-aligned features are worth with a right camera
            (benchmarks/pose_oracle.py); the camera head is trained either way.
        plane_resolution: side of each feature plane of ``triplane`` conditioning (4 times a power of two).
        plane_channels: features per plane of ``triplane`` conditioning (the trunk reads three times as many).
        encoders: AFF-NeRF only: ``two`` ResNet18 encoders, one for the shape code and one for the appearance code
            (the paper), or, beyond the paper, ``one`` whose pooled features give both codes through two linear
            layers (pixelNeRF's single encoder): a step saves one encoder's forward and backward pass.
        shape_pooling: AFF-NeRF only: how the shape encoder pools its feature maps into the code's inputs: ``mean``
            (the paper: the last stage averaged over the crop) or, beyond the paper, ``keypoints``: also where in the
            crop each channel of the second and third stages peaks (a spatial soft-argmax, Levine et al. 2016), so
            the code is told where the parts are, which the average forgets.
        code_noise: AFF-NeRF only, training only: Gaussian noise added to each code of a step, its standard
            deviation this times the spread (standard deviation) of that code dimension over the step's objects
            (0 = none, the paper). Beyond the paper: the decoder learns to give a plausible object for codes near
            the training objects' ones, as an encoder's code for a new object is (a denoising regulariser).
        code_kl_weight: AFF-NeRF only: > 0 makes the codes variational, beyond the paper. Each encoder also gives
            a log-variance per code dimension; training draws each code from that Gaussian around the encoder's
            code (the reparameterisation trick) and adds this weight times the KL divergence of the two Gaussians
            from N(0, I), summed over dimensions and averaged over objects (``loss/code_kl``), as a VAE's prior
            does: the code space stays smooth and centred, and the decoder learns which dimensions it may trust.
            The variances start small (:data:`affnerf.model.resnet.INITIAL_LOG_VARIANCE`).
            Prediction, evaluation and the fit use the mean. 0 = plain codes (the paper).
        crop_outside: what the encoders' crop shows where it leaves the image (an object near or cut off by the
            frame's edge): ``background`` (the paper's crop: the background colour, so a cut-off object looks like
            a whole one with a straight side) or ``checker``, beyond the paper: a black and white checkerboard
            (:func:`affnerf.data.crop.mark_outside`), so the encoders can tell where the view ends from where the
            object does. In training, in evaluation and in ``predict`` alike; the fit's target crop is never
            marked. From scratch beside the preset on two seeds it was level to behind (val40 mIoU −0.002 /
            −0.007, test64 −0.003 / −0.006; benchmarks/results/cut_inputs.md), so neither preset uses it.
        occupancy_density: density (per metre) above which a cell of an encoded object's occupancy grid counts as
            occupied (empty-space skipping at inference; the grid is dilated by one cell so thin parts survive).
    """

    kind: Literal["affnerf", "pixelnerf", "semantic-ray", "gsnerf", "pose-aware"] = "affnerf"
    code_dim: int = 32
    encoder_width: float = 1.0
    encoder_resolution: int = 224
    field_width: int = 256
    field_depth: int = 8
    color_width: int = 128
    affordance_width: int = 128
    pe_xyz: int = 10
    pe_dir: int = 4
    num_coarse: int = 64
    num_fine: int = 128
    coarse_field: Literal["own", "shared"] = "own"
    near: float = 0.1
    far: float = 1.5
    clip_to_cube: bool = False
    scene_half_extent: float = CANONICAL_HALF_EXTENT
    surface_density: float = 50.0
    surface_optical_depth: float = 0.0
    occupancy_density: float = 5.0
    conditioning: Literal["concat", "film", "triplane"] = "concat"
    geometry: Literal["density", "sdf"] = "density"
    view_affordance_weight: float = 0.0
    projection_camera: Literal["predicted", "given"] = "predicted"
    plane_resolution: int = 64
    plane_channels: int = 16
    encoders: Literal["two", "one"] = "two"
    shape_pooling: Literal["mean", "keypoints"] = "mean"
    code_noise: float = 0.0
    code_kl_weight: float = 0.0
    crop_outside: Literal["background", "checker"] = "background"


#: Fields of :class:`ModelConfig` that change how a trained model is sampled or used, not its weights: a checkpoint
#: may be resumed or loaded with other values of these. ``encoder_resolution`` is one: every encoder pools globally
#: (or samples its feature maps at projected points), so the same weights read crops of any side, though the codes
#: they give change until a further stage adapts them.
NON_ARCHITECTURE_FIELDS = (
    "encoder_resolution",
    "num_coarse",
    "num_fine",
    "near",
    "far",
    "clip_to_cube",
    "scene_half_extent",
    "surface_density",
    "surface_optical_depth",
    "occupancy_density",
    "projection_camera",
    "code_noise",
)
