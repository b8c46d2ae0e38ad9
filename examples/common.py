"""Shared helpers for the paper gallery: data paths, a Cycles CPU clay studio, panels, PNG output.

Every figure script builds its geometry with the `pointscale` package (and the add-on's
operators where a Blender user would use them), shows each panel with the same camera, renders
it with Cycles on the CPU and tiles the panels into one labelled strip with NumPy.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import bpy
import numpy as np
from mathutils import Vector

ROOT = Path(__file__).resolve().parents[1]
GALLERY = ROOT / "docs" / "gallery"
BACKGROUND = np.array([1.0, 1.0, 1.0])
CLAY = (0.62, 0.50, 0.40)
_T0 = time.perf_counter()


# ----------------------------------------------------------------------------- options, data


def data_dir() -> Path:
    """../shared/data next to the repository, or $POINTSCALE_DATA."""
    return Path(os.environ.get("POINTSCALE_DATA", ROOT / ".." / "shared" / "data")).resolve()


def model_path(name: str) -> Path | None:
    path = data_dir() / name
    return path if path.exists() else None


def parse_args(doc: str, argv=None):
    p = argparse.ArgumentParser(description=doc.strip().splitlines()[0])
    p.add_argument("--quick", action="store_true", help="tiny images at low sample counts (for the test)")
    p.add_argument("--out", type=Path, default=GALLERY, help="output folder (default docs/gallery)")
    args = p.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    return args


def need_models(*names):
    """Paths of the named models; exits with status 3 (the runner reports "skipped") when one is absent."""
    paths = [model_path(n) for n in names]
    missing = [n for n, p in zip(names, paths) if p is None]
    if missing:
        print(f"SKIP: {', '.join(missing)} not found in {data_dir()}", flush=True)
        sys.exit(3)
    return paths


def read_model(path):
    """(points (n, 3) float64, faces (m, 3) int32 or None) of a PLY file."""
    import pointscale.io

    m = pointscale.io.read_ply(path)
    faces = None
    if m.faces is not None and len(m.faces):
        faces = np.asarray([f for f in m.faces if len(f) == 3], dtype=np.int32)
    return m.points, faces


# Which way each scan faces once its +y is turned up: every figure shows it from the front.
FRONT = {"max_planck.ply": "-z", "igea.ply": "z", "bunny.ply": "z", "happy_buddha_scans.ply": "z"}


def scan(name: str):
    """(points, faces) of a scan from the data folder, upright, facing -y, its bounding box
    centred with largest side 2; exits as "skipped" when the scan is absent."""
    (path,) = need_models(name)
    points, faces = read_model(path)
    points, _, _ = normalise(align_up(points, up="y", front=FRONT[name]))
    return points, faces


def addon_decompose(studio, points, faces, name: str, levels: int = 4):
    """A mesh object decomposed by the add-on's own Decompose operator, as an artist would."""
    load_addon()
    obj = studio.mesh(points, faces, name)
    make_active(obj)
    obj.data.multiscale.levels = levels
    assert bpy.ops.pointscale.decompose() == {"FINISHED"}
    return obj


def log(msg: str) -> None:
    print(f"  [{time.perf_counter() - _T0:6.1f} s] {msg}", flush=True)


def finish(args, name: str, numbers: dict) -> None:
    """Prints the figure's numbers and writes them next to the image as <name>.json."""
    numbers = dict(numbers)
    numbers["seconds"] = round(time.perf_counter() - _T0, 1)
    (args.out / f"{name}.json").write_text(json.dumps(numbers, indent=1, default=_jsonable) + "\n")
    print(f"{name} numbers:", flush=True)
    for k, v in numbers.items():
        print(f"  {k}: {json.dumps(v, default=_jsonable)}", flush=True)


def exit_now() -> None:
    """Ends the figure's process once its files are written. bpy 4.5 can deadlock in its exit
    handlers (a condition variable destroyed while its file-closing thread still waits on it),
    which left finished figures hanging until the runner's timeout; the outputs are complete here."""
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)


def _jsonable(x):
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    return str(x)


def load_addon():
    """The add-on from this source tree (addon/), registered, as tests/blender do; returns the module."""
    import importlib.util

    name = "pointscale_addon"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(
            name, ROOT / "addon" / "__init__.py", submodule_search_locations=[str(ROOT / "addon")])
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
        module.register()
    return sys.modules[name]


def make_active(obj):
    for o in bpy.context.view_layer.objects:
        o.select_set(False)
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj


def read_key(obj, name):
    kb = obj.data.shape_keys.key_blocks[name]
    co = np.empty(len(kb.points) * 3, np.float32)
    kb.points.foreach_get("co", co)
    return co.reshape(-1, 3).astype(np.float64)


# ----------------------------------------------------------------------------- geometry helpers


def align_up(points, up: str = "z", front: str = "-y"):
    """Rotates a model so that its `up` axis becomes +z and its `front` axis -y (Blender's front view)."""
    axes = {"x": 0, "y": 1, "z": 2}

    def vec(s):
        v = np.zeros(3)
        v[axes[s[-1]]] = -1.0 if s.startswith("-") else 1.0
        return v

    u, f = vec(up), vec(front)
    r = np.cross(-f, u)  # right-handed: new x = new y (= -front) x new z (= up)
    R = np.stack([r, -f, u])  # rows: new x, new y, new z in old coordinates
    return np.asarray(points) @ R.T


def normalise(points, size: float = 2.0):
    """Centre of the bounding box at the origin and its largest side `size`; returns (points, scale, shift)."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    shift = -(lo + hi) / 2
    scale = size / float((hi - lo).max())
    return (points + shift) * scale, scale, shift


# ----------------------------------------------------------------------------- scene


class Studio:
    """An empty Cycles CPU scene with a clay material, a three-point sun rig plus a soft sky, and a
    camera fitted once to everything the figure will show (so all its panels share it)."""

    def __init__(self, quick: bool, width: int, height: int, samples: int = 48):
        bpy.ops.wm.read_factory_settings(use_empty=True)
        self.quick = quick
        self.scene = scene = bpy.context.scene
        scene.render.engine = "CYCLES"
        scene.cycles.device = "CPU"
        scene.cycles.samples = 4 if quick else samples
        scene.cycles.use_adaptive_sampling = True
        scene.cycles.adaptive_threshold = 0.02
        scene.cycles.use_denoising = True
        scene.cycles.denoiser = "OPENIMAGEDENOISE"
        scene.cycles.max_bounces = 4
        scene.cycles.diffuse_bounces = 2
        scene.cycles.glossy_bounces = 1
        scene.cycles.transmission_bounces = 0
        scene.cycles.volume_bounces = 0
        scene.cycles.transparent_max_bounces = 2
        scene.cycles.use_auto_tile = False
        scene.render.threads_mode = "AUTO"
        scene.render.film_transparent = True
        scene.render.resolution_percentage = 100
        self.scale = 0.3 if quick else 1.0
        scene.render.resolution_x = max(16, int(width * self.scale))
        scene.render.resolution_y = max(16, int(height * self.scale))
        scene.view_settings.view_transform = "AgX"
        scene.view_settings.look = "AgX - High Contrast"
        scene.render.image_settings.file_format = "PNG"
        scene.render.image_settings.color_mode = "RGBA"
        scene.render.image_settings.color_depth = "8"
        world = bpy.data.worlds.new("Sky")
        scene.world = world
        world.use_nodes = True
        bg = world.node_tree.nodes["Background"]
        bg.inputs["Color"].default_value = (0.82, 0.87, 1.0, 1.0)
        bg.inputs["Strength"].default_value = 0.3
        self.materials = {}
        self.camera = None
        self._tmp = Path(tempfile.mkdtemp(prefix="pointscale_gallery_"))

    # --- materials
    def clay(self, color=CLAY, name="Clay"):
        key = (name, tuple(color))
        if key in self.materials:
            return self.materials[key]
        mat = bpy.data.materials.new(name)
        mat.use_nodes = True
        bsdf = mat.node_tree.nodes["Principled BSDF"]
        bsdf.inputs["Base Color"].default_value = (*color, 1.0)
        bsdf.inputs["Roughness"].default_value = 0.65
        bsdf.inputs["Specular IOR Level"].default_value = 0.25
        self.materials[key] = mat
        return mat

    def attribute_material(self, attribute: str, name="Detail colour"):
        """Matte material whose base colour is a colour attribute (the add-on's `ms_detail_color`)."""
        mat = bpy.data.materials.new(name)
        mat.use_nodes = True
        nt = mat.node_tree
        bsdf = nt.nodes["Principled BSDF"]
        bsdf.inputs["Roughness"].default_value = 0.7
        bsdf.inputs["Specular IOR Level"].default_value = 0.2
        node = nt.nodes.new("ShaderNodeVertexColor")
        node.layer_name = attribute
        nt.links.new(node.outputs["Color"], bsdf.inputs["Base Color"])
        return mat

    # --- objects
    def mesh(self, points, faces=None, name="Model", material=None, smooth=True):
        """A mesh object from (n, 3) points and optional (m, 3) faces."""
        points = np.asarray(points, dtype=np.float32)
        me = bpy.data.meshes.new(name)
        me.vertices.add(len(points))
        me.vertices.foreach_set("co", points.reshape(-1))
        if faces is not None and len(faces):
            faces = np.asarray(faces, dtype=np.int32)
            me.loops.add(faces.size)
            me.polygons.add(len(faces))
            me.loops.foreach_set("vertex_index", faces.reshape(-1))
            me.polygons.foreach_set("loop_start", np.arange(0, faces.size, faces.shape[1], dtype=np.int32))
            me.polygons.foreach_set("use_smooth", np.full(len(faces), smooth))
        me.update(calc_edges=True)
        if faces is not None and len(faces) and not _consistent(faces, len(points)):
            import bmesh  # some scans (igea.ply) mix face windings: smooth shading needs them consistent

            bm = bmesh.new()
            bm.from_mesh(me)
            bmesh.ops.recalc_face_normals(bm, faces=bm.faces)
            bm.to_mesh(me)
            bm.free()
        obj = bpy.data.objects.new(name, me)
        self.scene.collection.objects.link(obj)
        me.materials.append(material or self.clay())
        return obj

    def points(self, points, radius: float, name="Points", material=None):
        """A vertex-only mesh shown as Cycles point-cloud spheres (Geometry Nodes: Mesh to Points)."""
        obj = self.mesh(points, None, name, material)
        ng = bpy.data.node_groups.new(f"{name} points", "GeometryNodeTree")
        ng.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
        ng.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
        gin = ng.nodes.new("NodeGroupInput")
        gout = ng.nodes.new("NodeGroupOutput")
        m2p = ng.nodes.new("GeometryNodeMeshToPoints")
        m2p.inputs["Radius"].default_value = radius
        setmat = ng.nodes.new("GeometryNodeSetMaterial")
        setmat.inputs["Material"].default_value = material or self.clay()
        ng.links.new(gin.outputs[0], m2p.inputs["Mesh"])
        ng.links.new(m2p.outputs["Points"], setmat.inputs["Geometry"])
        ng.links.new(setmat.outputs["Geometry"], gout.inputs[0])
        mod = obj.modifiers.new("Mesh to Points", "NODES")
        mod.node_group = ng
        return obj

    def resize(self, width: int, height: int):
        """Changes the output size; keep the aspect ratio so the fitted camera still frames the same view."""
        self.scene.render.resolution_x = max(16, int(width * self.scale))
        self.scene.render.resolution_y = max(16, int(height * self.scale))

    def set_points(self, obj, points):
        obj.data.vertices.foreach_set("co", np.asarray(points, dtype=np.float32).reshape(-1))
        obj.data.update()

    def render_shapes(self, obj, shapes) -> list:
        """One panel per shape: obj's vertices moved to each (n, 3) shape in turn, then rendered alone."""
        shapes = list(shapes)
        panels = []
        for s in shapes:
            self.set_points(obj, s)
            panels.append(self.render([obj]))
            log(f"panel {len(panels)}/{len(shapes)}")
        return panels

    # --- camera and lights
    def frame(self, points, direction=(0.0, -1.0, 0.0), up=(0.0, 0.0, 1.0), lens=60.0, margin=1.06,
              shift=(0.0, 0.0)):
        """Places the camera looking along `direction` so that all `points` (an (n, 3) array, e.g.
        every panel's geometry stacked) fit, and the sun rig around that view."""
        pts = np.asarray(points, dtype=np.float64)
        if len(pts) > 200000:
            pts = pts[np.random.default_rng(0).choice(len(pts), 200000, replace=False)]
        d = np.asarray(direction, float)
        d /= np.linalg.norm(d)
        u = np.asarray(up, float)
        r = np.cross(d, u)
        r /= np.linalg.norm(r)
        u = np.cross(r, d)
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        c = (lo + hi) / 2
        q = pts - c
        x, y, z = q @ r, q @ u, q @ d
        cx, cy = (x.max() + x.min()) / 2, (y.max() + y.min()) / 2
        c = c + cx * r + cy * u
        x, y = x - cx, y - cy
        cam_data = bpy.data.cameras.new("Camera")
        cam_data.lens = lens
        cam_data.sensor_fit = "AUTO"
        cam_data.clip_start = 1e-3
        cam_data.clip_end = 1e4
        res_x, res_y = self.scene.render.resolution_x, self.scene.render.resolution_y
        half_w = 0.5 * cam_data.sensor_width / lens  # tan(fov/2) along the longer side
        tx, ty = (half_w, half_w * res_y / res_x) if res_x >= res_y else (half_w * res_x / res_y, half_w)
        dist = max(float((np.abs(x) / tx + z).max()), float((np.abs(y) / ty + z).max())) * margin
        cam = bpy.data.objects.new("Camera", cam_data)
        self.scene.collection.objects.link(cam)
        cam.location = Vector(c - d * dist)
        cam.rotation_euler = Vector(d).to_track_quat("-Z", "Y").to_euler()
        cam_data.shift_x, cam_data.shift_y = shift
        # the track quaternion keeps +Y as up only approximately: build the exact frame instead
        from mathutils import Matrix

        R = Matrix([list(r), list(u), list(-d)]).transposed()
        cam.rotation_euler = R.to_euler()
        cam_data.clip_end = dist * 10 + 10
        cam_data.clip_start = dist * 1e-3
        self.scene.camera = cam
        self.camera = cam
        self._lights(r, u, -d)
        return cam

    def _lights(self, right, up, back):
        """Key (upper left, warm), fill (right, cool, weak), rim (behind, above): sun lights."""
        right, up, back = (np.asarray(v) for v in (right, up, back))
        rig = [
            ("Key", -0.75 * right + 0.8 * up + 0.9 * back, 3.2, (1.0, 0.96, 0.9), 12.0),
            ("Fill", 0.9 * right + 0.05 * up + 0.6 * back, 1.0, (0.88, 0.93, 1.0), 30.0),
            ("Rim", 0.35 * right + 0.9 * up - 1.0 * back, 2.2, (1.0, 1.0, 1.0), 8.0),
        ]
        for name, towards_light, strength, color, angle in rig:
            light = bpy.data.lights.new(name, "SUN")
            light.energy = strength
            light.color = color
            light.angle = np.radians(angle)
            obj = bpy.data.objects.new(name, light)
            self.scene.collection.objects.link(obj)
            v = Vector(-towards_light / np.linalg.norm(towards_light))  # light travels along -towards_light
            obj.rotation_euler = v.to_track_quat("-Z", "Y").to_euler()

    # --- rendering
    def render(self, show) -> np.ndarray:
        """Renders with only the objects in `show` visible; returns (h, w, 3) float RGB on the background."""
        show = set(o.name for o in show)
        for o in self.scene.collection.objects:
            if o.type in {"MESH", "CURVE", "FONT", "POINTCLOUD"}:
                o.hide_render = o.name not in show
        path = self._tmp / "panel.png"
        self.scene.render.filepath = str(path)
        with _quiet():
            bpy.ops.render.render(write_still=True)
        img = bpy.data.images.load(str(path))
        w, h = img.size
        a = np.empty(w * h * 4, np.float32)
        img.pixels.foreach_get(a)
        bpy.data.images.remove(img)
        a = a.reshape(h, w, 4)[::-1]
        rgb, alpha = a[..., :3], a[..., 3:4]
        return rgb * alpha + BACKGROUND * (1 - alpha)


def _consistent(faces, n) -> bool:
    """True when nearly every interior edge is used once in each direction (consistent winding)."""
    f = np.asarray(faces, dtype=np.int64)
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]) if f.shape[1] == 3 else \
        np.concatenate([f[:, [i, (i + 1) % f.shape[1]]] for i in range(f.shape[1])])
    key = e[:, 0] * n + e[:, 1]
    return len(np.unique(key)) > 0.99 * len(key)


class _quiet:
    """Silences Cycles' per-tile progress lines on stdout (C level) while rendering."""

    def __enter__(self):
        sys.stdout.flush()
        self.saved = os.dup(1)
        self.null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(self.null, 1)

    def __exit__(self, *exc):
        os.dup2(self.saved, 1)
        os.close(self.saved)
        os.close(self.null)
        return False


# ----------------------------------------------------------------------------- composing and saving


def label(text: str, width: int, size: int = 13, height: int | None = None) -> np.ndarray:
    """Dark text centred on the background colour: (h, w, 3) float, drawn with Blender's font."""
    import blf
    import imbuf

    height = height or int(size * 1.9)
    ib = imbuf.new((width, height))
    with blf.bind_imbuf(0, ib, display_name="sRGB"):
        blf.size(0, size)
        tw, th = blf.dimensions(0, text)
        blf.position(0, max(2, (width - tw) / 2), (height - size * 0.72) / 2, 0)
        blf.color(0, 1, 1, 1, 1)
        blf.draw_buffer(0, text)
    path = Path(tempfile.mkdtemp(prefix="pointscale_label_")) / "label.png"
    imbuf.write(ib, filepath=str(path))
    img = bpy.data.images.load(str(path))
    a = np.empty(width * height * 4, np.float32)
    img.pixels.foreach_get(a)
    bpy.data.images.remove(img)
    cover = a.reshape(height, width, 4)[::-1, :, 3:4]
    ink = np.array([0.15, 0.15, 0.17])
    return BACKGROUND * (1 - cover) + ink * cover


def tile(panels, labels=None, cols=None, title=None, quick=False) -> np.ndarray:
    """Panels (h, w, 3) of one size in rows of `cols`, each with its label underneath."""
    cols = cols or len(panels)
    h, w = panels[0].shape[:2]
    size = 8 if quick else 13
    cells = []
    for i, p in enumerate(panels):
        cell = p
        if labels is not None:
            cell = np.concatenate([p, label(labels[i], w, size)], axis=0)
        cells.append(cell)
    while len(cells) % cols:
        cells.append(np.ones_like(cells[0]) * BACKGROUND)
    rows = [np.concatenate(cells[i:i + cols], axis=1) for i in range(0, len(cells), cols)]
    out = np.concatenate(rows, axis=0)
    if title:
        out = np.concatenate([label(title, out.shape[1], size + 1, int((size + 1) * 2.2)), out], axis=0)
    return out


def stack(rows) -> np.ndarray:
    """Stacks tiled rows of slightly different widths, centred on the background."""
    w = max(r.shape[1] for r in rows)
    out = []
    for r in rows:
        pad = w - r.shape[1]
        left = np.ones((r.shape[0], pad // 2, 3)) * BACKGROUND
        right = np.ones((r.shape[0], pad - pad // 2, 3)) * BACKGROUND
        out.append(np.concatenate([left, r, right], axis=1))
    return np.concatenate(out, axis=0)


def write_png(path, rgb: np.ndarray) -> int:
    """(h, w, 3) float RGB in [0, 1] as an 8-bit PNG, by Blender's own image writer (the one the
    renders come from). Returns the file size."""
    a = np.clip(np.asarray(rgb, dtype=np.float32)[..., :3], 0.0, 1.0)
    h, w = a.shape[:2]
    rgba = np.concatenate([a, np.ones((h, w, 1), np.float32)], axis=2)[::-1]  # Blender's rows run bottom up
    # A byte image: its pixels are written to the file as they are, with no colour transform.
    img = bpy.data.images.new("pointscale_png", w, h, alpha=False, float_buffer=False)
    try:
        img.pixels.foreach_set(np.ascontiguousarray(rgba).reshape(-1))
        img.filepath_raw = str(path)
        img.file_format = "PNG"
        img.save()
    finally:
        bpy.data.images.remove(img)
    return Path(path).stat().st_size


def save(args, name: str, image: np.ndarray) -> Path:
    path = args.out / f"{name}.png"
    size = write_png(path, image)
    log(f"wrote {path} ({image.shape[1]}x{image.shape[0]} px, {size / 1024:.0f} KB)")
    return path
