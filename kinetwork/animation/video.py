"""Videos of an Animation without a browser: Pillow draws each frame as the player does
(the same camera, Lambert shading, faces sorted by depth); GIF by Pillow, MP4 by ffmpeg."""

import math
import os
import shutil
import subprocess

import numpy as np

from ..errors import ModelError
from .scene import FRAMES_SHOWN, perpendicular, unit_vector

_X, _Y = np.eye(3)[:2]


def find_ffmpeg():
    """An ffmpeg executable: imageio-ffmpeg's when installed, else one on the PATH, or None."""
    try:
        import imageio_ffmpeg
        return imageio_ffmpeg.get_ffmpeg_exe()
    except (ImportError, RuntimeError):
        return shutil.which("ffmpeg")


def write_gif(anim, path, fps, height=400):
    """Render ``anim`` (times fps apart) into an endlessly looping GIF."""
    from PIL import Image
    images = list(Raster(anim, height).images())
    # one palette for all frames, from a few of them and the pure colours of the shapes and
    # axes (thin lines are too few pixels to win a place on their own)
    sample = images[::max(1, len(images) // 4)][:4]
    swatch = Image.new("RGB", (sum(im.width for im in sample), sample[0].height + 8))
    for k, im in enumerate(sample):
        swatch.paste(im, (k * im.width, 0))
    colors = {_rgb(sh["color"]) for sh in anim["shapes"]} | set(Raster.AXES)
    for k, color in enumerate(sorted(colors)):
        swatch.paste(color, (8 * k, sample[0].height, 8 * k + 8, sample[0].height + 8))
    palette = swatch.quantize(colors=160, method=Image.Quantize.MEDIANCUT)
    frames = [im.quantize(palette=palette, dither=Image.Dither.NONE) for im in images]
    frames[0].save(path, format="GIF", save_all=True, append_images=frames[1:],
                   duration=round(1000 / fps), loop=0, optimize=False)


def write_mp4(anim, path, fps, height, ffmpeg):
    """Render ``anim`` into an H.264 MP4 through ``ffmpeg``."""
    raster = Raster(anim, height)
    w, h = raster.size
    cmd = [ffmpeg, "-loglevel", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24",
           "-s", f"{w}x{h}", "-r", f"{fps:g}", "-i", "-", "-c:v", "libx264", "-pix_fmt",
           "yuv420p", "-movflags", "+faststart", "-f", "mp4", os.fspath(path)]
    with subprocess.Popen(cmd, stdin=subprocess.PIPE, stderr=subprocess.PIPE) as proc:
        try:
            for im in raster.images():
                proc.stdin.write(im.tobytes())
        except BrokenPipeError:       # ffmpeg stopped: its words say why
            pass
        _, err = proc.communicate()
    err = err.decode(errors="replace").strip()
    if proc.returncode:
        raise ModelError(f"ffmpeg could not write {path}: {err.splitlines()[-1] if err else ''}")


class Raster:
    """Draws an Animation with Pillow, as the player does: the same camera (perspective,
    fitted to the bounds), Lambert shading, depth-sorted faces (painter's algorithm), drawn
    at twice the size and scaled down for smooth edges."""

    SUPER = 2
    AXES = ((220, 50, 50), (40, 160, 60), (50, 80, 220))

    def __init__(self, anim, height=400):
        self.anim, self.t = anim, np.asarray(anim["t"])
        view = anim["view"]
        up, d = np.asarray(view["up"], float), np.asarray(view["direction"], float)
        self.forward = -d
        self.right = unit_vector(np.cross(self.forward, up), perpendicular(self.forward))
        self.camup = np.cross(self.right, self.forward)
        self.tan = math.tan(math.radians(view["fov"]) / 2)
        lo, hi = (np.asarray(b, float) for b in anim["bounds"])
        margin = anim["scale"] / 5
        corners = np.array([[x, y, z] for x in (lo[0] - margin, hi[0] + margin)
                            for y in (lo[1] - margin, hi[1] + margin)
                            for z in (lo[2] - margin, hi[2] + margin)]) - view["target"]
        x, y, z = corners @ self.right, corners @ self.camup, corners @ self.forward
        aspect = float(np.clip(np.abs(x).max() / max(np.abs(y).max(), 1e-12), 0.75, 1.6))
        self.size = (2 * round(height * aspect / 2), 2 * round(height / 2))
        distance = 1.12 * max(np.max(np.abs(y) / self.tan - z),
                              np.max(np.abs(x) / (self.tan * aspect) - z))
        self.eye = np.asarray(view["target"], float) - distance * self.forward
        self.light = unit_vector(-self.forward + 0.6 * self.camup - 0.4 * self.right)
        ground = [s["frame"] for s in anim["shapes"] if s["kind"] == "grid"]
        small = [s for s in anim["shapes"] if s["kind"] == "axes" and s["frame"] not in ground]
        # as the player: a scene of many frames (an engine) is clearer without their axes
        self.shapes = [s for s in anim["shapes"] if len(small) <= FRAMES_SHOWN or s not in small]
        self.meshes = [_mesh(s) for s in self.shapes]

    def pose(self, k, i):
        frame = self.anim["frames"][k]
        row = min(i, len(frame["position"]) - 1)
        return np.asarray(frame["position"][row]), _rotation(frame["quaternion"][row])

    def images(self):
        for i in range(len(self.t)):
            yield self.image(i)

    def project(self, points):
        rel = points - self.eye
        z = rel @ self.forward
        f = self.size[1] * self.SUPER / 2 / self.tan
        x = self.size[0] * self.SUPER / 2 + f * (rel @ self.right) / np.maximum(z, 1e-9)
        y = self.size[1] * self.SUPER / 2 - f * (rel @ self.camup) / np.maximum(z, 1e-9)
        return np.stack([x, y], axis=-1), z

    def image(self, i):
        from PIL import Image, ImageDraw, ImageFont
        s = self.SUPER
        items = []
        for shape, mesh in zip(self.shapes, self.meshes):
            items += self._items(shape, mesh, i)
        im = Image.new("RGB", (self.size[0] * s, self.size[1] * s), (244, 245, 247))
        draw = ImageDraw.Draw(im)
        for _, kind, pts, color, width in sorted(items, key=lambda it: -it[0]):
            if kind == "face":
                draw.polygon(pts, fill=color)
            else:
                draw.line(pts, fill=color, width=max(1, round(width * s)), joint="curve")
        im = im.resize(self.size, Image.Resampling.LANCZOS)
        text = f"{self.anim['name']}    t = {self.t[i]:.2f} s"
        ImageDraw.Draw(im).text((10, 8), text, fill=(60, 60, 60),
                                font=ImageFont.load_default(size=13))
        return im

    def _items(self, shape, mesh, i):
        kind = shape["kind"]
        p, R = self.pose(shape["frame"], i)
        color = np.asarray(_rgb(shape["color"]), dtype=float)
        if kind in ("rod", "spring"):
            q, _ = self.pose(shape["to"], i)
            a, b = p, q
            if np.linalg.norm(b - a) < 1e-12:
                return []
            if kind == "spring":
                return self._lines([_helix(a, b, shape)], color, 2.5)
            verts, faces = _segment_cylinder(a, b, shape["diameter"])
            return self._faces(verts, faces, color)
        if kind == "axes":
            out = []
            for axis, c in zip(R.T, self.AXES):
                out += self._lines([np.array([p, p + shape["length"] * axis])], c, 2.5)
            return out
        verts, faces = mesh
        world = p + verts @ R.T
        if kind == "grid":
            return self._lines(world.reshape(-1, 2, 3), color * 0.9, 1.0, behind=True)
        return self._faces(world, faces, color)

    def _faces(self, verts, groups, color):
        """Items of the faces: ``groups`` are (F, k) arrays of vertex indices."""
        out = []
        pts, z = self.project(verts)
        for faces in groups:
            v = verts[faces]
            n = np.cross(v[:, 2] - v[:, 0], v[:, -1] - v[:, 1])    # robust at sphere poles
            norm = np.linalg.norm(n, axis=1)
            cos = np.abs(n @ self.light) / np.where(norm > 0, norm, 1.0)
            fills = np.clip(color * (0.5 + 0.5 * cos)[:, None], 0, 255).astype(int)
            depth = z[faces].mean(axis=1)
            visible = np.all(z[faces] > 1e-6, axis=1)
            out += [(depth[f], "face", [tuple(q) for q in pts[faces[f]]], tuple(fills[f]), 0)
                    for f in np.flatnonzero(visible)]
        return out

    def _lines(self, polylines, color, width, behind=False):
        out, fill = [], tuple(int(c) for c in np.clip(color, 0, 255))
        for line in polylines:
            pts, z = self.project(np.asarray(line))
            if np.all(z > 1e-6):
                depth = np.inf if behind else z.mean()
                out.append((depth, "line", [tuple(q) for q in pts], fill, width))
        return out


def _rotation(q):
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _rgb(color):
    return tuple(int(color[k:k + 2], 16) for k in (1, 3, 5))


def _mesh(shape):
    """(vertices in the shape's frame, faces as vertex index lists) of a solid or grid."""
    kind = shape["kind"]
    if kind == "grid":
        n, half = shape["divisions"], shape["size"] / 2
        normal = np.asarray(shape["normal"], float)
        u = perpendicular(normal, _X if abs(normal[0]) < 0.9 else _Y)
        w = np.cross(normal, u)
        c, s = np.asarray(shape["r_shape"], float), np.linspace(-half, half, n + 1)
        lines = [(c + u * k - w * half, c + u * k + w * half) for k in s]
        lines += [(c + w * k - u * half, c + w * k + u * half) for k in s]
        return np.array(lines).reshape(-1, 3), None
    if kind == "mesh":
        return (np.reshape(shape["vertices"], (-1, 3)),
                [np.reshape(np.asarray(shape["faces"], dtype=int), (-1, 3))])
    if kind not in ("box", "cylinder", "sphere"):
        return None
    ld = np.asarray(shape["length_direction"], float)
    wd = np.asarray(shape["width_direction"], float)
    basis = np.stack([ld * shape["length"], wd * shape["width"],
                      np.cross(ld, wd) * shape["height"]], axis=1)
    verts, faces = _UNIT[kind]
    if kind == "sphere":
        basis = np.stack([ld, wd, np.cross(ld, wd)], axis=1) * shape["length"]
    return np.asarray(shape["r_shape"], float) + verts @ basis.T, faces


def _unit_box(m=6):
    """From x = 0 to 1, y and z from -1/2 to 1/2; the sides cut in ``m`` as a cylinder's."""
    corners = [(-.5, -.5), (.5, -.5), (.5, .5), (-.5, .5)]
    v = np.array([[j / m, y, z] for j in range(m + 1) for y, z in corners])
    k = np.arange(4)
    sides = np.array([np.stack([4 * j + k, 4 * (j + 1) + k, 4 * (j + 1) + (k + 1) % 4,
                                4 * j + (k + 1) % 4], axis=1) for j in range(m)]).reshape(-1, 4)
    return v, [sides, np.stack([k, 4 * m + k])]


def _unit_cylinder(n=20, m=6):
    """Along x from 0 to 1, diameter 1; the sides cut in ``m`` rings, so the painter's
    sort keeps coaxial cylinders (a rod through a body's rod) in order."""
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    v = np.array([[j / m, np.cos(b) / 2, np.sin(b) / 2] for j in range(m + 1) for b in a])
    k = np.arange(n)
    sides = np.array([np.stack([j * n + k, j * n + (k + 1) % n, (j + 1) * n + (k + 1) % n,
                                (j + 1) * n + k], axis=1) for j in range(m)]).reshape(-1, 4)
    return v, [sides, np.stack([k, m * n + k])]


def _unit_sphere(n=16, m=9):
    lon, lat = np.linspace(0, 2 * np.pi, n, endpoint=False), np.linspace(0, np.pi, m)
    v = np.array([[0.5 - np.cos(b) / 2, np.sin(b) * np.cos(a) / 2, np.sin(b) * np.sin(a) / 2]
                  for b in lat for a in lon])
    k = np.arange(n)
    quads = np.array([np.stack([j * n + k, j * n + (k + 1) % n, (j + 1) * n + (k + 1) % n,
                                (j + 1) * n + k], axis=1) for j in range(m - 1)])
    return v, [quads.reshape(-1, 4)]


_UNIT = {"box": _unit_box(), "cylinder": _unit_cylinder(), "sphere": _unit_sphere()}


def _segment_cylinder(a, b, diameter):
    d = b - a
    ld = d / np.linalg.norm(d)
    wd = perpendicular(ld)
    basis = np.stack([d, wd * diameter, np.cross(ld, wd) * diameter], axis=1)
    verts, faces = _UNIT["cylinder"]
    return a + verts @ basis.T, faces


def _helix(a, b, shape, points_per_turn=16):
    d = b - a
    ld = d / np.linalg.norm(d)
    wd = perpendicular(ld)
    hd = np.cross(ld, wd)
    turns = shape["windings"]
    s = np.linspace(0, 1, turns * points_per_turn + 1)
    r = shape["diameter"] / 2 * np.where((s > 0.04) & (s < 0.96), 1.0, 0.0)
    angle = 2 * np.pi * turns * s
    return a + np.outer(s, d) + np.outer(r * np.cos(angle), wd) + np.outer(r * np.sin(angle), hd)

