"""URDF meshes found as ROS tools find them and drawn by the animation; the view framed on the
robot and upright.

Mesh files are written here by trimesh (a box and a fine sphere of known geometry), into the
folder layouts robots ship in: a ROS package (``package.xml``), ``ROS_PACKAGE_PATH``, a
relative path. What the animation draws is checked against that geometry.
"""

import os
import shutil

import numpy as np
import pytest
import trimesh

import kinetwork as kn
from kinetwork.animation import meshes
from kinetwork.animation.scene import animation_data
from kinetwork.urdf.meshes import resolve

ROBOT = """<?xml version="1.0"?>
<robot name="arm">
  <link name="base"/>
  <link name="link">
    <inertial><mass value="1"/><origin xyz="0.2 0 0"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
    <visual><origin xyz="0.1 0 0" rpy="0 0 1.5707963267948966"/>
      <geometry><mesh filename="{mesh}" scale="2 2 2"/></geometry></visual>
  </link>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="link"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/>
  </joint>
</robot>
"""


def package(tmp_path, name="my_robot", mesh="package://my_robot/meshes/link.stl"):
    """A ROS package folder ``name`` (package.xml, urdf/, meshes/) holding the robot whose
    link's mesh is a 0.1 m cube; the URDF's path."""
    root = tmp_path / "src" / "folder_of_another_name"
    (root / "urdf").mkdir(parents=True)
    (root / "meshes").mkdir()
    (root / "package.xml").write_text(f"<package><name>{name}</name></package>")
    trimesh.creation.box(extents=[0.1, 0.1, 0.1]).export(root / "meshes" / "link.stl")
    urdf = root / "urdf" / "arm.urdf"
    urdf.write_text(ROBOT.format(mesh=mesh))
    return urdf


def test_package_paths_resolve_as_ros_tools_resolve_them(tmp_path, monkeypatch):
    urdf = package(tmp_path)
    found = str(urdf.parent.parent / "meshes" / "link.stl")
    # a folder above the URDF whose package.xml names the package
    assert resolve("package://my_robot/meshes/link.stl", str(urdf.parent)) == found
    assert resolve("../meshes/link.stl", str(urdf.parent)) == found
    assert resolve("file://" + found, "/") == found
    assert resolve("package://other/meshes/link.stl", str(urdf.parent)) is None
    # ROS_PACKAGE_PATH: a folder holding the package under its name
    elsewhere = tmp_path / "ws"
    shutil.copytree(urdf.parent.parent, elsewhere / "other")
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(elsewhere))
    assert resolve("package://other/meshes/link.stl", "/") == str(
        elsewhere / "other" / "meshes" / "link.stl")


def test_a_link_mesh_is_drawn_where_the_urdf_puts_it(tmp_path):
    model = kn.from_urdf(package(tmp_path))
    entry, = model.layout["ground"]["meshes"]
    assert entry["replaces"] == ["link"] and os.path.isfile(entry["path"])
    res = kn.simulate(model, t_end=0.5, n_points=6)
    anim = animation_data(res)
    mesh, = [s for s in anim["shapes"] if s["kind"] == "mesh"]
    assert not [s for s in anim["shapes"] if s.get("component") == "link"
                and s["kind"] == "sphere"]          # the mesh stands in for the body
    # the cube scaled by 2 (0.2 m), turned 90 degrees about z, its centre at x = 0.1 in the
    # link frame: at every time, its corners are where that frame takes them
    local = np.reshape(mesh["vertices"], (-1, 3))
    assert np.allclose(np.ptp(local, axis=0), 0.2) and np.allclose(local.mean(axis=0),
                                                                   [0.1, 0, 0])
    frame = anim["frames"][mesh["frame"]]
    q = res["shoulder.q"]
    for i in (0, len(anim["t"]) - 1):
        w, x, y, z = frame["quaternion"][min(i, len(frame["quaternion"]) - 1)]
        assert abs(2 * np.arctan2(y, w) - q[i]) < 1e-9    # the link frame turns with q


def test_a_missing_mesh_is_left_out_and_the_rest_still_drawn(tmp_path):
    urdf = package(tmp_path, mesh="package://my_robot/meshes/gone.stl")
    model = kn.from_urdf(urdf)
    assert model.layout["ground"]["meshes"] == []
    assert model.layout["ground"]["urdf"]["visuals"][0]["path"] is None
    anim = animation_data(kn.simulate(model, t_end=0.2, n_points=3))
    assert [s for s in anim["shapes"] if s.get("component") == "link"]   # its sphere


def test_coarsening_keeps_the_shape_within_its_cells():
    sphere = trimesh.creation.icosphere(subdivisions=5, radius=1.0)     # 20480 triangles
    v, f = meshes.coarsened(np.asarray(sphere.vertices), np.asarray(sphere.faces), 500)
    assert 100 < len(f) <= 500 and f.max() == len(v) - 1
    r = np.linalg.norm(v, axis=1)
    assert np.abs(r - 1).max() < 0.1                # within a cell of the sphere
    # still closed around the centre: the coarse triangles' solid angles sum to 4 pi
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    num = np.einsum("ij,ij->i", a, np.cross(b, c))
    den = (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1) * np.linalg.norm(c, axis=1)
           + np.einsum("ij,ij->i", a, b) * np.linalg.norm(c, axis=1)
           + np.einsum("ij,ij->i", a, c) * np.linalg.norm(b, axis=1)
           + np.einsum("ij,ij->i", b, c) * np.linalg.norm(a, axis=1))
    assert abs(abs(np.sum(2 * np.arctan2(num, den))) - 4 * np.pi) < 1e-6


def test_the_view_is_framed_on_the_robot_not_on_a_part_that_runs_away():
    # a 1 m pendulum swinging, and a slider beside it falling freely for 5 s (123 m)
    model = kn.Model("runaway")
    world = model.add(kn.multibody.Ground("world", gravity=[0, 0, -9.81]))
    hinge = model.add(kn.multibody.Revolute("hinge", axis=[0, 1, 0], q0=1.0))
    bob = model.add(kn.multibody.RigidBody("bob", mass=1.0, r_cm=[1.0, 0, 0]))
    slide = model.add(kn.multibody.Prismatic("slide", axis=[0, 0, 1]))
    block = model.add(kn.multibody.RigidBody("block", mass=1.0))
    model.connect(world.frame, hinge.frame_a)
    model.connect(hinge.frame_b, bob.frame_a)
    model.connect(world.frame, slide.frame_a)
    model.connect(slide.frame_b, block.frame_a)
    anim = animation_data(kn.simulate(model, t_end=5.0, n_points=51))
    lo, hi = (np.asarray(b) for b in anim["bounds"])
    assert np.all(hi - lo < 3.0) and anim["view"]["up"] == [0.0, 0.0, 1.0]


def test_without_gravity_a_urdf_robot_is_still_shown_z_up(tmp_path):
    model = kn.from_urdf(package(tmp_path), gravity=(0.0, 0.0, 0.0))
    anim = animation_data(kn.simulate(model, t_end=0.1, n_points=2))
    assert anim["view"]["up"] == [0.0, 0.0, 1.0]
