"""The Python module as a user drives it (run by CTest: python3 -m pytest tests/python).

Environment (set by tests/python/CMakeLists.txt): PYTHONPATH holds the built module,
SOFTBODY_EXE the softbody program, SOFTBODY_ASSETS the assets folder.
"""
import os
import re
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import softbody as sb

ASSETS = os.environ["SOFTBODY_ASSETS"]
EXE = os.environ["SOFTBODY_EXE"]
DEFAULT = os.path.join(ASSETS, "scenes", "default.json")


def cube(size=0.4, centre=(0.0, 1.0, 0.0)):
    """A closed cube of 8 particles with its 12 outward triangles."""
    h = size / 2
    v = np.array([[x, y, z] for x in (-h, h) for y in (-h, h) for z in (-h, h)]) + centre
    faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                      [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    return v, faces


def cube_body(name="cube", centre=(0.0, 1.0, 0.0)):
    d = sb.BodyDef()
    d.name = name
    d.positions, d.surface = cube(centre=centre)
    return d


def cli_hash(scene, steps):
    out = subprocess.run([EXE, "run", scene, "--steps", str(steps)], check=True,
                         capture_output=True, text=True).stdout
    return int(re.search(r"state hash ([0-9a-f]{16})", out).group(1), 16)


# ---- zero-copy views ----

def test_views_share_the_worlds_memory_and_follow_each_step():
    s = sb.load_scene(DEFAULT)
    w = s.world
    b = s.body(0)
    x = w.positions(b)
    assert x.shape == (w.particle_count(b), 3) and x.dtype == np.float32
    before = np.array(x)
    s.step(30)
    again = w.positions(b)
    assert np.shares_memory(x, again)          # the same memory, not a copy
    assert not np.array_equal(x, before)       # the old view shows the new state
    assert np.array_equal(x, again)
    for view in (x, w.velocities(b), w.rest_positions(b), s.render_vertices(0)):
        assert not view.flags.writeable
        with pytest.raises(ValueError):
            view[0, 0] = 1.0
    r = s.render_vertices(0)
    assert np.shares_memory(r, s.render_vertices(0)) and r.flags.c_contiguous
    moved = np.array(r)
    s.step(10)
    assert not np.array_equal(r, moved)
    assert r.shape[1] == 3 and s.render_triangles(0).max() == r.shape[0] - 1


def test_views_stay_valid_while_bodies_are_added():
    w = sb.World()
    first = w.add_body(cube_body())
    x = w.positions(first)
    for i in range(64):  # the world's body table grows several times
        w.add_body(cube_body(f"c{i}", centre=(i * 1.0, 3.0, 0.0)))
    w.step(5)
    assert np.shares_memory(x, w.positions(first))
    assert np.array_equal(x, w.positions(first))


def test_a_view_keeps_its_world_alive():
    def make():
        w = sb.World()
        b = w.add_body(cube_body())
        w.step(3)
        return w.positions(b), np.array(w.positions(b))
    view, copy = make()  # the world object is gone from Python's side
    assert np.array_equal(view, copy)


def test_removing_a_viewed_body_is_refused_until_the_views_are_gone():
    w = sb.World()
    b = w.add_body(cube_body())
    v = w.velocities(b)
    with pytest.raises(RuntimeError, match=r"1 NumPy view\(s\) of body 'cube' are still alive"):
        w.remove_body(b)
    with pytest.raises(RuntimeError, match="still alive"):
        w.set_clusters(b, sb.ClusterDef())
    sliced = v[::2]  # a view of the view keeps the memory too
    del v
    with pytest.raises(RuntimeError, match="still alive"):
        w.remove_body(b)
    del sliced
    w.remove_body(b)
    assert not w.contains(b)


# ---- the same results as the program ----

def test_stepping_from_python_gives_the_programs_state_hash():
    s = sb.load_scene(DEFAULT)
    s.step(120)
    assert s.world.state_hash() == cli_hash(DEFAULT, 120)
    # The world alone (no render-mesh deform) steps to the same state.
    t = sb.load_scene(DEFAULT)
    t.world.step(120)
    assert t.world.state_hash() == s.world.state_hash()


def test_exports_from_python_equal_the_programs(tmp_path):
    steps, every = 40, 10
    subprocess.run([EXE, "run", DEFAULT, "--steps", str(steps), "--every", str(every),
                    "--export-pc2", str(tmp_path / "cli.pc2"),
                    "--export-gltf", str(tmp_path / "cli.glb"),
                    "--export-mesh", str(tmp_path / "cli.obj")],
                   check=True, capture_output=True)
    s = sb.load_scene(DEFAULT)
    dt = s.world.settings.time_step
    frames = steps // every + 1
    cache = sb.PointCache(s, str(tmp_path / "py.pc2"), sb.PointCacheFormat.PC2, frames, dt * every)
    take = sb.GltfTake(s, str(tmp_path / "py.glb"), frames, dt * every)
    sb.write_render_obj(s, str(tmp_path / "py.obj"), one_object=True)
    for k in range(frames):
        if k:
            s.step(every)
        cache.add_frame(s)
        take.add_frame(s)
    assert not (tmp_path / "py.pc2").exists()  # published by finish() only
    cache.finish()
    take.finish()
    for ext in ("pc2", "glb", "obj"):
        assert (tmp_path / f"py.{ext}").read_bytes() == (tmp_path / f"cli.{ext}").read_bytes(), ext


# ---- errors ----

def test_bad_shapes_and_values_name_what_is_wrong():
    w = sb.World()
    b = w.add_body(cube_body())
    ok = np.array(w.positions(b))
    with pytest.raises(ValueError, match=r"positions must have shape \(8, 3\), got \(5, 2\)"):
        w.set_state(b, np.zeros((5, 2)), np.zeros((8, 3)))
    with pytest.raises(ValueError, match=r"velocities must have shape \(8, 3\), got \(24,\)"):
        w.set_state(b, ok, np.zeros(24))
    with pytest.raises(ValueError, match="numeric"):
        w.set_state(b, [["a", "b", "c"]] * 8, ok)
    # Any float array of the right shape: float64, int, Fortran order, a strided slice.
    big = np.zeros((16, 3))
    big[::2] = ok
    w.set_state(b, big[::2], np.asfortranarray(np.zeros((8, 3), dtype=np.float32)))
    assert np.allclose(w.positions(b), ok)
    w.set_state(b, ok, np.zeros((8, 3), dtype=np.int64))
    with pytest.raises(ValueError, match="not finite"):
        w.set_state(b, np.full((8, 3), np.nan), np.zeros((8, 3)))
    p = w.params(b)
    p.alpha = 1.5
    with pytest.raises(ValueError, match="alpha"):
        w.set_params(b, p)
    st = w.settings
    st.time_step = -1.0
    with pytest.raises(ValueError, match="timeStep"):
        w.settings = st
    d = cube_body()
    d.surface = np.array([[0, 1, 3]])  # not closed
    with pytest.raises(ValueError, match="surface"):
        w.add_body(d)
    with pytest.raises(ValueError):
        w.step(-1)


def test_scene_and_file_errors_carry_the_programs_messages(tmp_path):
    with pytest.raises(sb.SceneError, match="/nonexistent/x.json: cannot open the file"):
        sb.load_scene("/nonexistent/x.json")
    bad = tmp_path / "bad.json"
    bad.write_text('{"bodies": [{"mesh": "x.obj", "scale": -1}]}')
    with pytest.raises(sb.SceneError, match=r"bad.json.*bodies\[0\]"):
        sb.load_scene(str(bad))
    s = sb.load_scene(DEFAULT)
    with pytest.raises(sb.FileError, match="/nonexistent/dir/t.pc2"):
        sb.PointCache(s, "/nonexistent/dir/t.pc2", sb.PointCacheFormat.PC2, 2, 0.1)
    with pytest.raises(IndexError):
        s.render_vertices(99)
    with pytest.raises(RuntimeError, match="scene's bodies"):
        s.world.add_body(cube_body())


# ---- threads ----

def test_step_releases_the_gil():
    s = sb.load_scene(DEFAULT)
    counter = [0]
    done = threading.Event()

    def count():
        while not done.is_set():
            counter[0] += 1
            time.sleep(0)  # gives the GIL back at once: the main thread never waits long
    old = sys.getswitchinterval()
    # With a long switch interval the other thread gets the GIL only when it is released
    # on purpose: it can count while step() runs only if step() releases the GIL.
    sys.setswitchinterval(30.0)
    try:
        t = threading.Thread(target=count)
        t.start()
        before = counter[0]
        s.step(600)
        during = counter[0] - before
    finally:
        done.set()
        sys.setswitchinterval(old)
        t.join()
    assert during > 0


def test_a_stepping_world_refuses_other_calls():
    s = sb.load_scene(os.path.join(ASSETS, "scenes", "pile.json"))
    errors = []
    # A call lands inside step() only if it is made while the other thread steps, which is a
    # matter of timing; step in batches until one did (each batch takes about a second here, and
    # the poll runs every millisecond), so the refusal is checked, not just allowed.
    for _ in range(30):
        t = threading.Thread(target=lambda: s.step(200))
        t.start()
        while t.is_alive() and not errors:
            try:
                s.world.positions(s.body(0))
            except RuntimeError as e:
                errors.append(str(e))
            time.sleep(0.001)
        t.join()
        if errors:
            break
    assert errors, "no call was made while the world stepped in another thread"
    for e in errors:
        assert "stepping in another thread" in e
    # Once the stepping thread has ended, the same call is accepted again.
    assert s.world.positions(s.body(0)).shape[1] == 3
    assert s.world.time > 0


# ---- cages ----

def test_bind_and_deform_reproduce_an_affine_map():
    cage_v, cage_f = cube(size=2.0, centre=(0.0, 0.0, 0.0))
    rng = np.random.default_rng(7)
    points = rng.uniform(-0.9, 0.9, (200, 3))
    e = sb.bind(points, cage_v, cage_f)
    assert (e.mesh_vertex_count, e.cage_vertex_count) == (200, 8)
    a = np.array([[1.2, 0.1, 0.0], [0.0, 0.9, 0.2], [0.1, 0.0, 1.1]])
    moved = e.deform(cage_v @ a.T + [0.5, -1.0, 2.0])
    assert np.abs(moved - (points @ a.T + [0.5, -1.0, 2.0])).max() < 1e-5
    with pytest.raises(ValueError, match=r"cage_positions must have shape \(8, 3\)"):
        e.deform(np.zeros((7, 3)))
    with pytest.raises(ValueError, match="not closed"):
        sb.bind(points, cage_v, cage_f[:-1])  # an open cage
    with pytest.raises(ValueError):
        sb.bind(points, cage_v, cage_f[:, ::-1])  # inside out


def test_bind_methods():
    cage_v, cage_f = cube(size=2.0, centre=(0.0, 0.0, 0.0))
    rng = np.random.default_rng(8)
    points = rng.uniform(-0.8, 0.8, (100, 3))
    a = np.array([[1.1, 0.2, 0.0], [0.0, 0.9, 0.1], [0.1, 0.0, 1.2]])
    # harmonic: its grid of 16 cells along 2 m is accurate to about a cell (0.125 m).
    for method, tol in (("mvc", 1e-5), ("rbf", 1e-5), ("harmonic", 0.25)):
        e = sb.bind(points, cage_v, cage_f, method=method, resolution=16)
        assert e.method == method
        moved = e.deform(cage_v @ a.T + [1.0, 2.0, 3.0])
        # mvc and rbf reproduce affine maps exactly; harmonic to its grid's precision.
        assert np.abs(moved - (points @ a.T + [1.0, 2.0, 3.0])).max() < tol, method
    # green reproduces similarities (not every affine map), from the cage's vertices alone.
    e = sb.bind(points, cage_v, cage_f, method="green")
    assert e.method == "green"
    c, s = np.cos(0.4), np.sin(0.4)
    similar = 1.3 * np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    moved = e.deform(cage_v @ similar.T + [1.0, 2.0, 3.0])
    assert np.abs(moved - (points @ similar.T + [1.0, 2.0, 3.0])).max() < 1e-5
    with pytest.raises(ValueError, match="outside the cage"):
        sb.bind(np.array([[0.0, 0.0, 0.0], [1.5, 0.0, 0.0]]), cage_v, cage_f, method="green")
    with pytest.raises(ValueError, match="method must be"):
        sb.bind(points, cage_v, cage_f, method="ffd-bspline")
    with pytest.raises(ValueError, match=r"resolution must be in \[4, 64\]"):
        sb.bind(points, cage_v, cage_f, method="harmonic", resolution=2)
    with pytest.raises(ValueError, match=r"shape must be in \[0, 10\]"):
        sb.bind(points, cage_v, cage_f, method="rbf", shape=-1.0)


def test_help_documents_units_and_shapes():
    assert "float32 (P, 3)" in sb.World.positions.__doc__
    assert "GIL" in sb.World.step.__doc__
