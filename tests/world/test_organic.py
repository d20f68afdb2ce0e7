"""Curved, photo-textured scenes: each primitive against a closed-form or hand-computed hit, the
photo texture's view consistency, and the registered scenes (finite, labelled, seeded, listed)."""
import numpy as np
import pytest

from ddp_lite.core.camera import Camera, look_at
from ddp_lite.world.solids import Capsule, Cone, Ellipsoid
from ddp_lite.world.terrain import HeightField
from ddp_lite.world.photo_texture import PhotoTexture
from ddp_lite.world.render import Cylinder, Plane, Sphere, render
from ddp_lite.world.scenes import SCENES, list_scenes, make_scene, register_scene
from ddp_lite.world.textures import Texture
from ddp_lite.core.views import LABELS

NEW = ("hills", "sculpture", "logs")
FLAT = Texture("flat")
PHOTO = PhotoTexture("gravel", 0.5)


def _rays(n=400, seed=0, origin=(0.1, -0.4, -3.0), spread=0.5):
    """n unit-ish directions (n, 3) roughly along +z from ``origin``."""
    rng = np.random.default_rng(seed)
    d = np.column_stack([rng.uniform(-spread, spread, n), rng.uniform(-spread, spread, n), np.ones(n)])
    return np.asarray(origin, float), d


def test_ellipsoid_with_equal_radii_is_the_sphere_and_scaling_is_exact():
    o, d = _rays()
    sphere = Sphere((0.2, -0.1, 1.0), 0.7, FLAT)
    for yaw in (0.0, 37.0):  # a round ellipsoid does not care about its yaw
        t = Ellipsoid((0.2, -0.1, 1.0), (0.7, 0.7, 0.7), FLAT, yaw).intersect(o, d)
        np.testing.assert_allclose(t, sphere.intersect(o, d), rtol=1e-12)
    assert np.isfinite(t).mean() > 0.05 and np.isinf(t).any()  # some hits, some misses
    # semi-axes (a, b, c) along x, y, z: from (0, 0, -5) straight ahead the hit is at 5 - c;
    # along x from (-5, 0, 0) at 5 - a, with yaw 90° the x and z axes swap
    e = Ellipsoid((0.0, 0.0, 0.0), (0.5, 0.3, 1.2), FLAT)
    assert e.intersect(np.array([0.0, 0.0, -5.0]), np.array([[0.0, 0.0, 1.0]]))[0] == pytest.approx(3.8)
    assert e.intersect(np.array([-5.0, 0.0, 0.0]), np.array([[1.0, 0.0, 0.0]]))[0] == pytest.approx(4.5)
    turned = Ellipsoid((0.0, 0.0, 0.0), (0.5, 0.3, 1.2), FLAT, 90.0)
    assert turned.intersect(np.array([0.0, 0.0, -5.0]), np.array([[0.0, 0.0, 1.0]]))[0] == pytest.approx(4.5)
    assert np.isinf(e.intersect(np.array([0.0, 0.0, -5.0]), np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.2]]))).all()
    x = np.array([[0.0, 0.0, -1.2], [0.5, 0.0, 0.0], [0.0, -0.3, 0.0]])  # points on it: normals ±axes
    _, st, n = e.surface(x)
    np.testing.assert_allclose(n, [[0, 0, -1], [1, 0, 0], [0, -1, 0]], atol=1e-12)
    assert np.all(np.isfinite(st))


def test_ellipsoid_seen_from_inside_is_hit_at_its_wall_with_normals_towards_the_viewer():
    dome = Ellipsoid((0.0, 0.0, 0.0), (2.0, 2.0, 2.0), FLAT, inside=True)
    o, d = np.zeros(3), np.random.default_rng(1).normal(size=(50, 3))
    t = dome.intersect(o, d)
    np.testing.assert_allclose(t * np.linalg.norm(d, axis=1), 2.0, rtol=1e-12)  # distance = radius
    _, _, n = dome.surface(o + t[:, None] * d)
    assert np.all(np.einsum("ij,ij->i", n, d) < 0)  # facing back along the rays


def test_cylinder_seen_side_on_hits_at_distance_minus_radius_on_any_axis():
    rng = np.random.default_rng(2)
    for _ in range(5):
        a = rng.normal(size=3)
        w = rng.normal(size=3)
        w /= np.linalg.norm(w)
        L, r, D = 2.0, 0.3, 4.0
        cyl = Cone(tuple(a), tuple(a + L * w), r, r, FLAT)
        side = np.cross(w, rng.normal(size=3))
        side /= np.linalg.norm(side)  # perpendicular to the axis
        centre = a + 0.4 * L * w
        t = cyl.intersect(centre + D * side, -side[None])[0]
        assert t == pytest.approx(D - r, rel=1e-10)
        _, _, n = cyl.surface((centre + r * side)[None])
        np.testing.assert_allclose(n[0], side, atol=1e-9)
        # end-on along the axis: the cap at a, at distance D
        assert cyl.intersect(a - D * w, w[None])[0] == pytest.approx(D, rel=1e-10)
        # parallel to the axis but outside the radius, or pointing away: misses
        assert np.isinf(cyl.intersect(a + 2 * r * side - D * w, w[None])[0])
        assert np.isinf(cyl.intersect(centre + D * side, side[None])[0])


def test_vertical_cone_with_equal_radii_matches_the_existing_cylinder():
    o, d = _rays(n=600, seed=3, origin=(0.05, -0.6, -2.0), spread=0.4)
    old = Cylinder(0.1, 1.0, (-0.8, 0.2), 0.35, FLAT)  # axis x=0.1, z=1.0, y from -0.8 to 0.2
    new = Cone((0.1, 0.2, 1.0), (0.1, -0.8, 1.0), 0.35, 0.35, FLAT)
    t_old, t_new = old.intersect(o, d), new.intersect(o, d)
    assert np.array_equal(np.isfinite(t_old), np.isfinite(t_new)) and np.isfinite(t_new).mean() > 0.05
    np.testing.assert_allclose(t_new[np.isfinite(t_new)], t_old[np.isfinite(t_old)], rtol=1e-9)


def test_cone_side_on_hits_its_local_radius():
    # axis along +x from (0, 0, 5): radius 0.5 at x = 0 down to 0.1 at x = 2; a ray in the plane
    # x = h perpendicular to the axis meets the circle of radius r(h)
    cone = Cone((0.0, 0.0, 5.0), (2.0, 0.0, 5.0), 0.5, 0.1, FLAT)
    for h in (0.3, 1.0, 1.7):
        r = 0.5 + (0.1 - 0.5) * h / 2.0
        assert cone.intersect(np.array([h, 0.0, 0.0]), np.array([[0.0, 0.0, 1.0]]))[0] == pytest.approx(5.0 - r)
    assert np.isinf(cone.intersect(np.array([2.5, 0.0, 0.0]), np.array([[0.0, 0.0, 1.0]]))[0])  # beyond the tip
    # a pointed cone: the normal tilts towards the tip by atan(k)
    _, _, n = cone.surface(np.array([[1.0, 0.0, 5.0 - 0.3]]))
    k = -0.2
    np.testing.assert_allclose(n[0], np.array([-k, 0.0, -1.0]) / np.hypot(1.0, k), atol=1e-9)


def test_cone_and_capsule_first_hits_against_dense_sampling():
    # oblique and steep rays: the hit lies on the solid's boundary and nothing before it is inside
    rng = np.random.default_rng(6)
    a, b = np.array([0.2, 0.3, 3.0]), np.array([-0.3, -0.9, 3.6])
    w = (b - a) / np.linalg.norm(b - a)
    L = np.linalg.norm(b - a)

    def inside_cone(p):  # (..., 3) → bool, radius 0.6 at a to 0.05 at b
        q = p - a
        h = q @ w
        rho = np.linalg.norm(q - h[..., None] * w, axis=-1)
        return (h >= 0) & (h <= L) & (rho <= 0.6 + (0.05 - 0.6) * h / L)

    def inside_capsule(p):  # radius 0.2 around the segment
        h = np.clip((p - a) @ w, 0, L)
        return np.linalg.norm(p - (a + h[..., None] * w), axis=-1) <= 0.2

    for solid, inside in ((Cone(tuple(a), tuple(b), 0.6, 0.05, FLAT), inside_cone),
                          (Capsule(tuple(a), tuple(b), 0.2, FLAT), inside_capsule)):
        # from the side, and from beyond the tip looking down the axis (rays steeper than the wall)
        for o, spread in ((np.zeros(3), 0.5), (b + 1.5 * w, 0.25)):
            d = (a + 0.5 * (b - a) + rng.normal(0, spread, (400, 3))) - o  # aimed near the solid
            t = solid.intersect(o, d)
            hit = np.isfinite(t)
            assert 0.2 < hit.mean() < 0.95
            s = np.linspace(0.0, 1.0, 1500) * np.where(hit, t, 8.0)[:, None]  # (400, 1500)
            inner = inside(o + s[..., None] * d[:, None, :])
            assert not inner[:, :-1].any()  # never inside before the hit (or anywhere, for a miss)
            at = o + t[hit, None] * d[hit]
            assert inside(at + 1e-6 * d[hit] / np.linalg.norm(d[hit], axis=1, keepdims=True)).all()  # enters


def test_capsule_end_on_and_side_on():
    a, b, r = np.array([0.0, 0.0, 3.0]), np.array([0.0, 0.0, 5.0]), 0.05
    rod = Capsule(tuple(a), tuple(b), r, FLAT)
    assert rod.intersect(np.zeros(3), np.array([[0.0, 0.0, 1.0]]))[0] == pytest.approx(3.0 - r)  # round end
    assert rod.intersect(np.array([-2.0, 0.0, 4.0]), np.array([[1.0, 0.0, 0.0]]))[0] == pytest.approx(2.0 - r)
    assert np.isinf(rod.intersect(np.array([-2.0, 0.2, 4.0]), np.array([[1.0, 0.0, 0.0]]))[0])
    _, _, n = rod.surface(np.array([[0.0, 0.0, 3.0 - r], [-r, 0.0, 4.0]]))
    np.testing.assert_allclose(n, [[0, 0, -1], [-1, 0, 0]], atol=1e-12)


FIELD = HeightField(PHOTO, bumps=((0.5, 4.0, 0.8, 1.2), (-1.5, 6.0, -0.3, 0.8)), waves=((1.3, 0.7, 0.4, 0.06),),
                    base=0.1, max_distance=30.0)


def test_height_field_straight_down_hits_h_and_normals_follow_the_gradient():
    rng = np.random.default_rng(4)
    x, z = rng.uniform(-3, 3, 200), rng.uniform(1, 8, 200)
    h = FIELD.height(x, z)
    hits = np.array([FIELD.intersect(np.array([xi, -5.0, zi]), np.array([[0.0, 1.0, 0.0]]))[0] for xi, zi in zip(x, z)])
    np.testing.assert_allclose(hits, 5.0 - h, atol=1e-6)  # y = -h, from y = -5
    # normals: the analytic gradient against central differences
    eps = 1e-6
    gx = (FIELD.height(x + eps, z) - FIELD.height(x - eps, z)) / (2 * eps)
    gz = (FIELD.height(x, z + eps) - FIELD.height(x, z - eps)) / (2 * eps)
    _, st, n = FIELD.surface(np.column_stack([x, -h, z]))
    expected = -np.column_stack([gx, np.ones_like(gx), gz])
    np.testing.assert_allclose(n, expected / np.linalg.norm(expected, axis=1, keepdims=True), atol=1e-7)
    np.testing.assert_allclose(st, np.column_stack([x, z]))
    lo, hi = FIELD.bounds()
    assert lo <= h.min() and h.max() <= hi


def test_height_field_oblique_rays_find_the_first_crossing():
    eye = np.array([0.0, -1.5, 0.0])
    _, d = _rays(n=300, seed=5, origin=eye, spread=0.6)
    t = FIELD.intersect(eye, d)
    hit = np.isfinite(t)
    assert hit.mean() > 0.3 and np.isinf(t[d[:, 1] < -0.2]).all()  # rays going up miss
    p = eye + t[hit, None] * d[hit]
    np.testing.assert_allclose(p[:, 1], -FIELD.height(p[:, 0], p[:, 2]), atol=1e-5)  # on the surface
    # nothing earlier along the ray is underground (dense check, 2 mm steps)
    s = np.linspace(0.0, 1.0, 2000)[None, :] * t[hit, None]  # (M, 2000)
    q = eye + s[..., None] * d[hit, None, :]
    assert np.all(q[..., 1] + FIELD.height(q[..., 0], q[..., 2]) <= 1e-6)
    # without bumps or waves it is the plane y = -base
    flat = HeightField(PHOTO, base=0.25)
    ground = Plane((0, -0.25, 0), (0, -1, 0), (1, 0, 0), PHOTO)
    near = ground.intersect(eye, d) < flat.max_distance
    assert near.any() and np.all(np.isinf(flat.intersect(eye, d)[~near]))  # beyond max_distance: no hit
    np.testing.assert_allclose(flat.intersect(eye, d)[near], ground.intersect(eye, d)[near], rtol=1e-9)


def test_photo_texture_samples_tiles_and_labels():
    with pytest.raises(ValueError, match="image"):
        PhotoTexture("not_a_photo")
    with pytest.raises(ValueError, match="scale"):
        PhotoTexture("coffee", scale=0.0)
    tex = PhotoTexture("coffee", scale=0.4, variation=0.0)
    assert tex.kind == "photo" and tex.label == 3 and PhotoTexture("grass").image_array.shape[2] == 3
    h, w = tex.image_array.shape[:2]
    s = np.linspace(-1.0, 1.0, 801)
    t = np.full_like(s, 0.13)
    local = np.zeros((len(s), 3))

    def colour(s, t, seed=0):
        return tex.albedo(local, np.column_stack([s, t]), seed)

    c = colour(s, t)
    assert c.shape == (len(s), 3) and 0 <= c.min() and c.max() <= 1
    # mirrored repeat: period two tiles (2·scale across, 2·scale·h/w along), mirror at a tile border
    np.testing.assert_allclose(colour(s + 0.8, t), c, atol=1e-9)
    np.testing.assert_allclose(colour(s, t + 0.8 * h / w), c, atol=1e-9)
    border = 0.4 - tex.shift(0)[0]  # where s + shift crosses one image width
    np.testing.assert_allclose(colour(border - s / 10, t), colour(border + s / 10, t), atol=1e-9)
    assert not np.allclose(colour(s, t, seed=1), c)  # the seed moves the photo
    # a photo's pixel colour, unchanged by the sampling at a texel centre
    ts = tex.shift(0)
    texel = np.array([[(10.5 / w) * 0.4 - ts[0] + 0.8, (7.5 / w) * 0.4 - ts[1] + 0.8 * h / w]])  # + a period
    np.testing.assert_allclose(tex.albedo(np.zeros((1, 3)), texel, 0)[0], tex.image_array[7, 10], atol=1e-6)


def test_photo_textured_point_has_the_same_colour_in_two_views():
    prims, rig = SCENES["sculpture"][0](np.random.default_rng(0))
    eye0, eye1 = np.array(rig["eye"]) + [-0.2, 0.0, 0.0], np.array(rig["eye"]) + [0.3, 0.05, 0.1]
    cam0 = Camera.from_fov(32, 24, 60.0, look_at(eye0, rig["target"]))
    rgb0, depth0, label0 = render(prims, cam0, supersample=1)
    checked = 0
    for v, u in ((20, 8), (18, 24), (12, 16), (4, 6)):  # ground, ground, blob, dome wall
        X = cam0.world_from_cam[:3, :3] @ (np.linalg.inv(cam0.K) @ [u, v, 1.0] * depth0[v, u]) + eye0
        cam1 = Camera.from_fov(32, 24, 60.0, look_at(eye1, rig["target"]))
        x_cam = cam1.cam_from_world[:3, :3] @ X + cam1.cam_from_world[:3, 3]
        p = cam1.K @ x_cam / x_cam[2]
        K = cam1.K.copy()  # shift the principal point so that X lands on the centre of a pixel
        K[0, 2] += 16 - p[0]
        K[1, 2] += 12 - p[1]
        rgb1, depth1, _ = render(prims, Camera(K, cam1.cam_from_world, 32, 24), supersample=1)
        if abs(depth1[12, 16] - x_cam[2]) > 1e-4 * x_cam[2]:
            continue  # occluded in view 1
        assert label0[v, u] == 3
        np.testing.assert_allclose(rgb1[12, 16], rgb0[v, u], atol=1e-5)  # same point, same colour
        checked += 1
    assert checked >= 3 and rgb0.std() > 0.05


@pytest.fixture(scope="module")
def small():
    return {name: make_scene(name, size=(24, 32), n_views=2, seed=0) for name in NEW}


def test_new_scenes_render_finite_labelled_and_listed(small):
    names = list_scenes()
    for name in NEW:
        assert name in names and len(names[name]) > 20
        scene = small[name]
        for view in scene.views + scene.right:
            assert np.all(np.isfinite(view.depth)) and view.depth.min() > 0.5
            assert 0 <= view.rgb.min() and view.rgb.max() <= 1 and view.rgb.std() > 0.05
        labels = scene.labels[0]
        assert set(np.unique(labels)) <= set(LABELS) and (labels == 3).mean() > 0.5  # mostly photo-textured
        assert scene.meta["d_max"] <= (70.0 if name == "hills" else 10.0)
    assert (small["hills"].labels[0] == 0).mean() > 0.1  # the sky


def test_new_scenes_change_with_the_seed(small):
    for name in NEW:
        other = make_scene(name, size=(24, 32), n_views=1, seed=1)
        assert np.abs(other[0].depth - small[name][0].depth).max() > 0.05  # another layout
        assert np.abs(other[0].rgb - small[name][0].rgb).mean() > 0.01


def test_register_scene_refuses_to_shadow_a_scene():
    def _hills(rng):  # same name as the builder, different module
        return [], {}
    with pytest.raises(ValueError, match="already registered"):
        register_scene("hills", _hills, "an impostor")
    with pytest.raises(ValueError, match="name"):
        register_scene("Not A Name", _hills, "x")
    assert SCENES["hills"][0].__module__ == "ddp_lite.world.organic"
