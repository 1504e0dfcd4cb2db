"""``affnerf view``: a viser web viewer of a prediction, a dataset object or a mesh.

The scene holds the mesh split by affordance class (one node per class, in the palette's colours, each with a GUI
checkbox and a legend line giving its surface area), the gripper at each grasp (the best one dark, a slider shows
the best k), and the input image as a camera frustum and in the GUI panel. Use :func:`build_scene` on a server of
your own, or :func:`serve`.
"""

from __future__ import annotations

import html
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import viser
import viser.transforms as vtf

from affnerf.viewer.loading import GraspModel, MeshPart, load_grasps, load_image, load_parts
from affnerf.viewer.sources import InputCamera, ViewerSources, find_sources

#: Gripper colours, apart from the affordance palette: the best grasp dark and opaque, the others light and
#: see-through.
BEST_GRASP_COLOR, OTHER_GRASP_COLOR, OTHER_GRASP_OPACITY = (35, 35, 45), (225, 225, 235), 0.6
#: From where the initial view looks at the object (front-right, above; the front is -y).
VIEW_DIRECTION = np.array([0.45, -1.0, 0.6])
#: Vertical field of view of the initial view (viser's default), radians.
VIEW_FOV = math.radians(75.0)
#: OpenGL camera axes -> OpenCV camera axes (viser draws frustums in the OpenCV convention).
GL_TO_CV = np.diag([1.0, -1.0, -1.0, 1.0])


@dataclass(frozen=True)
class ViewContent:
    """Everything the viewer shows, loaded and checked before anything is drawn."""

    sources: ViewerSources
    parts: list[MeshPart]
    grasps: list[GraspModel]
    image: np.ndarray | None


@dataclass
class SceneHandles:
    """The viser handles :func:`build_scene` made, for scripts and tests.

    Attributes:
        content: what is shown.
        meshes: one node per part, keyed by class id (None for an unlabelled mesh).
        toggles: the checkbox of each part, same keys.
        grippers: one node per grasp, best first.
        top_k: the slider choosing how many grasps are shown (None without grasps).
        frustum: the input camera (None without an input image).
        centre: centre of the mesh's bounding box.
        radius: half the diagonal of the mesh's bounding box.
    """

    content: ViewContent
    meshes: dict[int | None, viser.MeshHandle | viser.GlbHandle] = field(default_factory=dict)
    toggles: dict[int | None, viser.GuiCheckboxHandle] = field(default_factory=dict)
    grippers: list[viser.MeshHandle] = field(default_factory=list)
    top_k: viser.GuiSliderHandle | None = None
    frustum: viser.CameraFrustumHandle | None = None
    centre: np.ndarray = field(default_factory=lambda: np.zeros(3))
    radius: float = 0.1


def load_content(path: Path) -> ViewContent:
    """Find and load what PATH shows (see :mod:`affnerf.viewer.sources`).

    Raises:
        AffnerfError: with one line naming the file at fault.
    """
    sources = find_sources(Path(path))
    parts = load_parts(sources.mesh)
    grasps = load_grasps(sources.grasps) if sources.grasps is not None else []
    camera = sources.camera
    image = load_image(camera.image) if camera is not None and camera.image is not None else None
    return ViewContent(sources, parts, grasps, image)


def build_scene(server: viser.ViserServer, path: Path, top_k: int = 5) -> SceneHandles:
    """Load PATH (an output folder or a mesh) and show it on ``server``.

    Args:
        server: the viser server.
        path: a prediction folder, a dataset object folder, a grasps folder, or a mesh file.
        top_k: grasps shown at first (best first).

    Raises:
        AffnerfError: with one line naming the file at fault (nothing is added then).
    """
    return show_content(server, load_content(path), top_k)


def show_content(server: viser.ViserServer, content: ViewContent, top_k: int = 5) -> SceneHandles:
    """Add loaded content to ``server``: lighting, mesh parts and legend, grippers, input camera, initial view."""
    handles = SceneHandles(content)
    server.gui.set_panel_label(f"affnerf view: {content.sources.mesh.parent.name}")
    server.scene.set_up_direction("+z")
    # The default environment washes the palette out; this one keeps the colours true.
    server.scene.configure_environment_map("warehouse", environment_intensity=0.5)
    _add_parts(server, content.parts, handles)
    _add_grasps(server, content.grasps, handles, top_k)
    if content.sources.camera is not None:
        _add_camera(server, content.sources.camera, content.image, handles)
    _set_initial_view(server, handles)
    return handles


def legend_html(parts: list[MeshPart]) -> str:
    """HTML lines of the legend: a colour swatch, the class name, its surface area (cm^2) and share of the total."""
    total = sum(p.area for p in parts) or 1.0
    lines = []
    for p in parts:
        swatch = (
            f'<span style="display:inline-block;width:0.9em;height:0.9em;margin-right:0.4em;'
            f'border:1px solid #0006;background:rgb{p.color}"></span>'
        )
        text = f"{html.escape(p.name)}: {p.area * 1e4:.1f} cm² ({100.0 * p.area / total:.0f} %)"
        lines.append(f'<div style="display:flex;align-items:center;font-size:0.85em">{swatch}{text}</div>')
    return '<div style="padding:0 0.75em">' + "".join(lines) + "</div>"


def _add_parts(server: viser.ViserServer, parts: list[MeshPart], handles: SceneHandles) -> None:
    """One mesh node per part, the legend and a visibility checkbox per part."""
    vertices = np.concatenate([np.asarray(p.mesh.vertices) for p in parts])
    lo, hi = vertices.min(0), vertices.max(0)
    handles.centre, handles.radius = (lo + hi) / 2.0, max(float(np.linalg.norm(hi - lo)) / 2.0, 1e-3)
    labelled = parts[0].label is not None
    with server.gui.add_folder("Affordances" if labelled else "Mesh"):
        server.gui.add_html(legend_html(parts))
        for p in parts:
            key = "unlabelled" if p.label is None else f"{p.label:02d}_{p.name.replace(' ', '_')}"
            if p.label is None and p.mesh.visual.kind is not None:  # keep the file's own colours
                node = server.scene.add_mesh_trimesh(f"/mesh/{key}", p.mesh)
            else:
                node = server.scene.add_mesh_simple(f"/mesh/{key}", p.mesh.vertices, p.mesh.faces, color=p.color)
            toggle = server.gui.add_checkbox(p.name, initial_value=True, hint=f"Show the {p.name} faces.")
            toggle.on_update(_visibility_setter(node, toggle))
            handles.meshes[p.label], handles.toggles[p.label] = node, toggle
    server.scene.add_grid(
        "/ground",
        width=4 * handles.radius,
        height=4 * handles.radius,
        plane="xy",
        cell_size=0.05,
        section_size=0.25,
        position=(handles.centre[0], handles.centre[1], lo[2]),
    )


def _visibility_setter(node: viser.SceneNodeHandle, toggle: viser.GuiCheckboxHandle):
    """A checkbox callback that shows or hides ``node``."""

    def update(_event: object) -> None:
        node.visible = bool(toggle.value)

    return update


def _add_grasps(server: viser.ViserServer, grasps: list[GraspModel], handles: SceneHandles, top_k: int) -> None:
    """The gripper at every grasp (the best dark), a slider for how many are shown and a line about the best."""
    if not grasps:
        if handles.content.sources.grasps is not None:
            with server.gui.add_folder("Grasps"):
                server.gui.add_markdown(f"{handles.content.sources.grasps.name} lists no grasps.")
        return
    shown = max(0, min(top_k, len(grasps)))
    for g in grasps:
        best = g.rank == 0
        color, opacity = (BEST_GRASP_COLOR, None) if best else (OTHER_GRASP_COLOR, OTHER_GRASP_OPACITY)
        node = server.scene.add_mesh_simple(
            f"/grasps/{g.rank:03d}", g.mesh.vertices, g.mesh.faces, color=color, opacity=opacity, visible=g.rank < shown
        )
        handles.grippers.append(node)
    with server.gui.add_folder("Grasps"):
        server.gui.add_markdown(_best_grasp_text(grasps[0], len(grasps)))
        slider = server.gui.add_slider("shown (best first)", 0, len(grasps), 1, shown)

        @slider.on_update
        def _(_event: object) -> None:
            for rank, node in enumerate(handles.grippers):
                node.visible = rank < slider.value

    handles.top_k = slider


def _best_grasp_text(best: GraspModel, count: int) -> str:
    """Markdown about the best grasp (drawn dark)."""
    parts = [f"{count} grasp{'s' if count != 1 else ''}; best (dark): width {best.width * 100:.1f} cm"]
    if best.epsilon is not None:
        parts.append(f"ε = {best.epsilon:.4f}")
    if best.affordance:
        parts.append(f"contacts on {' / '.join(best.affordance)}")
    return ", ".join(parts) + "."


def _add_camera(
    server: viser.ViserServer, camera: InputCamera, image: np.ndarray | None, handles: SceneHandles
) -> None:
    """The input camera as a frustum (with the image in it) and the image in the GUI panel."""
    c2w_cv = camera.c2w @ GL_TO_CV
    wxyz = vtf.SO3.from_matrix(c2w_cv[:3, :3]).wxyz
    distance = float(np.linalg.norm(camera.c2w[:3, 3] - handles.centre))
    scale = float(np.clip(0.6 * handles.radius, 0.01, 0.5 * distance))  # about the object's size
    handles.frustum = server.scene.add_camera_frustum(
        "/input_camera",
        fov=camera.fov_y,
        aspect=camera.aspect,
        scale=scale,
        image=image,
        wxyz=wxyz,
        position=c2w_cv[:3, 3],
        color=(40, 40, 40),
        thickness=2.0,
        thickness_units="screen",
    )
    with server.gui.add_folder("Input"):
        if image is not None:
            name = camera.image.name if camera.image is not None else "input"
            server.gui.add_image(image, label=name)
        server.gui.add_markdown(camera.note)
        toggle = server.gui.add_checkbox("show camera", initial_value=True)
        toggle.on_update(_visibility_setter(handles.frustum, toggle))


def initial_view(centre: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """(camera position, look-at point) that frame a sphere of ``radius`` around ``centre`` with some margin.

    Example:
        >>> eye, at = initial_view(np.zeros(3), 0.1)
        >>> bool(eye[1] < 0 and eye[2] > 0), at.tolist()
        (True, [0.0, 0.0, 0.0])
    """
    direction = VIEW_DIRECTION / np.linalg.norm(VIEW_DIRECTION)
    distance = 1.6 * radius / math.sin(VIEW_FOV / 2.0)
    centre = np.asarray(centre, np.float64)
    return centre + distance * direction, centre


def _set_initial_view(server: viser.ViserServer, handles: SceneHandles) -> None:
    """Start (and "Reset View") looking at the object from the front, z up."""
    eye, at = initial_view(handles.centre, handles.radius)
    server.initial_camera.position = eye
    server.initial_camera.look_at = at
    server.initial_camera.up = (0.0, 0.0, 1.0)
    server.initial_camera.near = max(1e-3, 0.01 * handles.radius)


def serve(
    path: Path, host: str = "127.0.0.1", port: int = 8080, block: bool = True, top_k: int = 5
) -> viser.ViserServer:
    """Serve the viewer of PATH on http://HOST:PORT.

    The content is loaded before the server starts, so bad input opens no port. Viser takes the next free port
    when PORT is taken (and any free one for 0); the URL printed has the port in use.

    Args:
        path: an output folder or a mesh (see :func:`build_scene`).
        host: address to listen on (127.0.0.1: this machine only).
        port: port to listen on.
        block: wait until Ctrl-C and then stop the server; False returns the running server (call ``.stop()``).
        top_k: grasps shown at first.

    Raises:
        AffnerfError: with one line naming the file at fault.
    """
    content = load_content(Path(path))
    server = viser.ViserServer(host=host, port=port, label="affnerf", verbose=False)
    try:
        show_content(server, content, top_k)
    except BaseException:
        server.stop()
        raise
    print(f"affnerf view: http://{host}:{server.get_port()}  ({content.sources.mesh})", flush=True)
    if not block:
        return server
    try:
        while True:
            time.sleep(1.0)
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()
    return server
