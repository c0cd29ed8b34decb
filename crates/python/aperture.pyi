"""aperture: glTF 2.0 render sessions with thin-lens depth of field, numpy images and batched
ray queries (SPEC §9). See docs/python.md."""

from collections.abc import Sequence
from os import PathLike
from typing import Any, Literal, TypedDict

import numpy as np
import numpy.typing as npt

__version__: str

_Path = str | PathLike[str]
_Vectors = npt.ArrayLike  # (N, 3) float32 or float64, C- or F-ordered
_Bound = float | npt.ArrayLike  # one number, or (N,) numbers
_Matrix = npt.ArrayLike  # 4x4, as math writes it (translation in the last column)
_Convention = Literal["auto", "gltf", "blender"]

class LoadError(Exception):
    """The file could not be loaded (or loaded again after an edit)."""

class RenderError(Exception):
    """A render, denoise or write failed."""

class Primitive(TypedDict, total=False):
    """One primitive's geometry (``positions`` and ``triangles`` required)."""

    positions: npt.ArrayLike  # (N, 3) floats
    triangles: npt.ArrayLike  # (M, 3) integer vertex indices
    normals: npt.ArrayLike  # (N, 3) floats; flat normals without
    uvs: npt.ArrayLike  # (N, 2) floats, texture coordinates set 0

class Hits(TypedDict):
    t: npt.NDArray[np.float32]
    primitive: npt.NDArray[np.int32]
    instance: npt.NDArray[np.int32]
    mesh: npt.NDArray[np.int32]
    u: npt.NDArray[np.float32]
    v: npt.NDArray[np.float32]
    normal: npt.NDArray[np.float32]
    hit: npt.NDArray[np.bool_]

class CameraRays(TypedDict):
    origins: npt.NDArray[np.float32]
    directions: npt.NDArray[np.float32]
    pixels: npt.NDArray[np.uint32]
    samples: npt.NDArray[np.uint32]

class Triangles(TypedDict):
    vertices: npt.NDArray[np.float32]
    indices: npt.NDArray[np.uint32]
    instance: npt.NDArray[np.int32]
    primitive: npt.NDArray[np.int32]

class RenderResult:
    """A render: unpacks as ``image, passes = result``."""

    image: npt.NDArray[np.float32]
    """H×W×4, linear, premultiplied R, G, B, A (the EXR's beauty)."""
    passes: dict[str, npt.NDArray[np.float32]]
    """H×W×C arrays by their EXR layer names ("Depth", "Normal", "Denoising Albedo", …)."""
    channels: dict[str, list[str]]
    """Each pass's channel names ("Depth": ["Z"], "Normal": ["X", "Y", "Z"], …)."""
    header: dict[str, Any]
    """The EXR header aperture render writes."""
    samples: int
    """Samples taken over the whole image."""
    def __len__(self) -> int: ...
    def __getitem__(self, i: int) -> Any: ...

class Render:
    """A progressive render (``scene.start``)."""

    samples: int
    """Samples every pixel has so far."""
    target: int
    """The samples asked for (spp)."""
    done: bool
    """Every sample taken, or cancelled."""
    def step(self, samples: int | None = None) -> int:
        """Renders the next `samples` samples of every pixel (None: the doubling schedule
        1, 1, 2, 4, …); returns the samples each pixel has now."""
    def image(self, denoise: bool | None = None) -> RenderResult:
        """The film so far: denoised when the render was started with ``denoise=True``
        (``denoise=False``: the noisy film; ``True`` without a denoised start: ValueError)."""
    def cancel(self) -> None:
        """Stops the render (also during a step, from another thread)."""

class Scene:
    """A loaded glTF file: render it, edit it in place, query rays against it."""

    path: str
    def info(self) -> dict[str, Any]:
        """What the scene holds, with the keys of ``aperture info --json``."""
    def render(
        self,
        *,
        width: int | None = None,
        height: int | None = None,
        spp: int = 64,
        camera: str | int | None = None,
        seed: int = 0,
        passes: str | Sequence[str] = "default",
        denoise: bool = False,
        denoise_quality: Literal["high", "balanced", "fast"] | None = None,
        denoise_prefilter: Literal["accurate", "fast", "none"] | None = None,
        oidn: str | None = None,
        sample_offset: int = 0,
        max_bounces: int = 12,
        clamp_direct: float = 0.0,
        clamp_indirect: float = 0.0,
        filter: Literal["box", "gaussian", "blackman-harris"] = "blackman-harris",
        sampler: Literal["sobol", "random"] = "sobol",
        env: str | Sequence[float] | None = None,
        env_rotation: float = 0.0,
        env_strength: float = 1.0,
        override_material: Literal["diffuse"] | None = None,
        bvh_quality: Literal["auto", "fast", "medium", "high"] = "auto",
        noise_threshold: float | None = None,
        min_spp: int | None = None,
        transmission: _Convention | None = None,
        single_sided: _Convention | None = None,
        no_energy_compensation: bool = False,
        time: float | None = None,
        frame: int | None = None,
        fps: float | None = None,
        motion_blur: bool | None = None,
        shutter: float | None = None,
        shutter_position: Literal["start", "center", "end"] | None = None,
        motion_steps: int | None = None,
        threads: int | None = None,
    ) -> RenderResult:
        """Renders with aperture render's options (same names, same defaults)."""
    def start(self, **options: Any) -> Render:
        """A progressive render with `render`'s options."""
    def set_camera(
        self,
        camera: str | int | None = None,
        matrix: _Matrix | None = None,
        *,
        fstop: float | None = ...,
        focus_distance: float | None = ...,
        aperture_radius: float | None = ...,
        focus_object: str | None = ...,
        lens: float | None = ...,
        sensor_width: float | None = ...,
        sensor_height: float | None = ...,
        sensor_fit: str | None = ...,
        blades: int | None = ...,
        rotation: float | None = ...,
        ratio: float | None = ...,
        use_dof: bool | None = ...,
        aperture_vignetting: float | None = ...,
        distortion_k1: float | None = ...,
        distortion_k2: float | None = ...,
        distortion_k3: float | None = ...,
        distortion_p1: float | None = ...,
        distortion_p2: float | None = ...,
        chromatic_lateral: float | None = ...,
        chromatic_longitudinal: float | None = ...,
        aperture_image: str | int | None = ...,
        lens_prescription: str | Sequence[Sequence[float]] | None = ...,
    ) -> None:
        """Moves the camera's node and sets its depth-of-field and lens keys (None removes a
        key; the lens keys are docs/lenses.md's). `aperture_image` (a path relative to the glTF
        file's folder, or a texture index) is read and decoded by the edit;
        `lens_prescription` is a lens file's path there or rows of [radius, thickness, IOR,
        aperture diameter] in mm. A bad value, or a file that cannot be read, raises
        ValueError naming the camera and the key, and changes nothing."""
    def set_transform(
        self,
        node: int | str,
        matrix: _Matrix | None = None,
        *,
        translation: Sequence[float] | None = None,
        rotation: Sequence[float] | None = None,
        scale: Sequence[float] | None = None,
    ) -> None:
        """Replaces a node's local transform (``matrix``), or the given components of its
        stored TRS (``rotation`` a unit quaternion x, y, z, w)."""
    def set_material(
        self,
        material: int | str,
        *,
        base_color: Sequence[float] = ...,
        metallic: float = ...,
        roughness: float = ...,
        emissive: Sequence[float] = ...,
        emissive_strength: float = ...,
        alpha_cutoff: float = ...,
        normal_scale: float = ...,
        occlusion_strength: float = ...,
        ior: float = ...,
        specular: float = ...,
        specular_color: Sequence[float] = ...,
    ) -> None:
        """Sets material factors."""
    def set_light(
        self,
        light: int,
        *,
        color: Sequence[float] = ...,
        intensity: float = ...,
        range: float = ...,
        inner_cone_angle: float = ...,
        outer_cone_angle: float = ...,
    ) -> None:
        """Sets a KHR_lights_punctual light's values."""
    def set_geometry(self, mesh: int, primitives: Sequence[Primitive]) -> None:
        """Gives a glTF mesh new geometry, one dict per primitive in order (as if the file
        stored those arrays; each primitive keeps its material). Loads the file again."""
    def set_visible(self, node: int | str, visible: bool) -> None:
        """Shows or hides a node and what it carries."""
    def intersect(
        self,
        origins: _Vectors,
        directions: _Vectors,
        tmin: _Bound | None = None,
        tmax: _Bound | None = None,
        threads: int | None = None,
    ) -> Hits:
        """Closest hits of N rays."""
    def occluded(
        self,
        origins: _Vectors,
        directions: _Vectors,
        tmax: _Bound | None = None,
        tmin: _Bound | None = None,
        threads: int | None = None,
    ) -> npt.NDArray[np.bool_]:
        """Whether each ray is blocked between tmin and tmax."""
    def camera_rays(
        self,
        width: int,
        height: int | None = None,
        lens_samples: int = 16,
        seed: int = 0,
        camera: str | int | None = None,
    ) -> CameraRays:
        """The thin-lens primary rays aperture bench-rays times (its primary_tile set)."""
    def triangles(self) -> Triangles:
        """The scene's world-space triangles, one copy per instance (for another ray library)."""

def load(
    path: _Path,
    *,
    scene: int | None = None,
    variant: str | int | None = None,
    time: float | None = None,
    frame: int | None = None,
    fps: float = 24.0,
    animation: str | int | None = None,
    aperture_radius: float | None = None,
    fstop: float | None = None,
    focus_distance: float | None = None,
    focus_object: str | int | None = None,
    no_dof: bool = False,
    max_memory: int | str | None = None,
    transmission: _Convention = "auto",
    single_sided: _Convention = "auto",
    geometry: dict[int, Sequence[Primitive]] | None = None,
) -> Scene:
    """Loads a .gltf or .glb file with aperture render's load options; ``geometry`` draws
    those meshes (by index) from the given arrays instead of the file's."""

def write(
    path: _Path,
    image: RenderResult | npt.ArrayLike,
    passes: dict[str, npt.ArrayLike] | None = None,
    *,
    exposure: float = 0.0,
    view: Literal["standard", "agx"] = "standard",
    transparent: bool = False,
    sixteen_bit: bool = False,
) -> None:
    """Writes a render (EXR with passes and header, or PNG) or a plain numpy image."""
