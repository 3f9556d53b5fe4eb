"""3-D animation of a run: the scene, the poses of its frames, and the players.

``animation_data(results)`` gives everything a player needs as one JSON-able dict, the
*Animation*; ``animate(results, "anim.html")`` (also ``res.animate``) writes it into one
self-contained HTML page with the three.js player of ``kinetwork/assets/player.js`` inlined
(no network needed to open it), and renders GIF or MP4 files of the same scene without a
browser. ``kinetwork animate MODEL --html out.html --gif out.gif`` does both from a file.

The Animation (``"format": "kinetwork.animation"``, version 1)::

    {"format": "kinetwork.animation", "version": 1, "name": "double_pendulum",
     "t": [0.0, 0.01, ...],                     # the time grid [s]
     "frames": [                                # every frame of the scene
       {"name": "shoulder.frame_b",             # a port there, or "mass1.cm"
        "ports": ["shoulder.frame_b", "link1.frame_a", "mass1.frame_a"],
        "position": [[x, y, z], ...],           # origin in the world [m], one row per t
        "quaternion": [[w, x, y, z], ...]},     # orientation in the world, scalar first
       ...],
     "shapes": [{"kind": "cylinder", "frame": 1, ...}, ...],      # what is drawn (below)
     "scale": 2.1,                              # the model's size [m] (see below)
     "bounds": [[xmin, ymin, zmin], [xmax, ymax, zmax]],          # frame origins, whole run
     "view": {"up": [0, 1, 0], "target": [x, y, z], "direction": [x, y, z], "fov": 35}}

A frame that never moves (the ground and what is welded to it) has one row of position and
quaternion instead of one per time. Every connection set of frames is one frame (a joint's
frame_b and the bodies fixed there share their pose), named after its first port in model
order; each body adds its centre of mass (``"<body>.cm"``, oriented as its frame_a). The
poses come from ``System.f_frames``, the kinematics frame probes read, evaluated over the
whole grid in one mapped CasADi call, so ``frames[k]["position"]`` is what a frame probe on
those ports records. The camera looks from ``target + distance * direction`` with ``up``
opposite to gravity; a player picks the distance that fits ``bounds`` in its window.

Shapes. Every shape has ``kind``, ``component`` (whose shape it is; null for the scene's own)
and ``color`` ("#rrggbb"):

- ``box``, ``cylinder``, ``sphere``, as Modelica's Shape: on ``frame``, starting at ``r_shape``
  (resolved in the frame), ``length`` along the unit ``length_direction``, ``width`` along the
  unit ``width_direction`` (orthogonal to it) and ``height`` along their cross product. A
  cylinder's diameter is its width; a sphere's diameter is its length, its centre
  ``r_shape + length/2 * length_direction``.
- ``rod``: a cylinder of ``diameter`` between the origins of ``frame`` and ``to``.
- ``spring``: a coil of ``diameter``, ``wire`` thickness and ``windings`` turns between the
  origins of ``frame`` and ``to``.
- ``axes``: arrows of ``length`` along x (red), y (green), z (blue) of ``frame``.
- ``grid``: a square of ``size`` with ``divisions`` lines per side, centred at ``r_shape`` in
  ``frame``, normal to ``normal``.

What is drawn, with nothing given: revolute and cylindrical joints a short cylinder along
their axis, prismatic joints a rail over the run's travel and a slider, spherical and
universal joints a sphere, planar joints a plate; fixed translations and rotations a rod
from frame_a to frame_b; a rigid body a sphere at its centre of mass (larger for heavier
bodies) on a thin rod from frame_a; line forces a coil (a damper a thick rod); the ground a
floor grid under the motion and an axes triad; every frame small axes. Sizes are fractions
of ``scale``, the largest extent of the frame origins over the run (Modelica's nominal
length): joints L/10 long and L/20 wide, rods L/40, bodies L/9. Bodies with looks of their
own are drawn as Modelica draws them: ``BodyBox``/``BodyCylinder`` from ``r_shape`` along
``length_direction`` (default ``r - r_shape``) with ``length``, ``width``, ``height``,
``diameter`` (defaults as Modelica's: the distance, and a twentieth of it), ``BodySphere``
a sphere of ``diameter`` at frame_a; a ``RigidBody`` with ``shape`` ("box", "cylinder",
"sphere") is that shape centred at its centre of mass, ``shape_size`` = (length along
frame_a's x, width along y, height along z; a cylinder's diameter is the width, a sphere's
the length). ``color`` is three numbers 0-255 (Modelica's), or 0-1 when none exceeds 1, or
a "#rrggbb" string.
"""

from .files import animate, cli_animate, html_page, player_script
from .scene import FORMAT, VERSION, animation_data
from .video import find_ffmpeg, write_gif, write_mp4

__all__ = ["FORMAT", "VERSION", "animate", "animation_data", "cli_animate", "find_ffmpeg",
           "html_page", "player_script", "write_gif", "write_mp4"]
