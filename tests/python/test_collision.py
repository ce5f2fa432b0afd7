"""Collision through the bindings: shapes, filters, the three query modes,
the resize-on-ESIZE loop of Linkage.collide, errors. Expected values are
closed forms (spheres on a straight chain overlap their neighbours by
2 r - 1) or brute force written here in numpy."""

import itertools

import numpy as np
import pytest

import aqs


def chain(n, radius, joined=True):
    L = aqs.Linkage()
    for i in range(n):
        b = L.add_body(1.0, (0.5, 0, 0), [0.1, 0, 0, 0, 0.1, 0, 0, 0, 0.1])
        L.add_joint("revolute", i - 1, b, pos=(1.0 if i else 0.0, 0, 0), axis=(0, 0, 1))
        L.add_shape(b, "sphere", [radius])
    L.set_collide_joined(joined)
    L.finalize()
    return L


def test_chain_contacts_closed_form_and_resize():
    # 100 neighbours overlap: more than the first buffer of 64, so the ESIZE
    # path of collide() resizes from the returned total.
    with chain(101, 0.6) as L:
        for mode in ("lazy", "full", "brute"):
            c = np.sort(L.collide(mode), order=["shape_a", "shape_b"])
            assert c.dtype == aqs.CONTACT_DTYPE
            assert len(c) == 100
            assert np.array_equal(c["body_b"], c["body_a"] + 1)
            np.testing.assert_allclose(c["depth"], 0.2, rtol=0, atol=1e-12)
            np.testing.assert_allclose(c["nx"], 1.0, rtol=0, atol=1e-12)
        assert L.any_contact()
        L.set_collide_joined(False)
        assert len(L.collide()) == 0 and not L.any_contact()


def test_random_positions_against_numpy_brute_force():
    # Spheres only: a contact exists iff the centres are closer than the sum
    # of the radii; depth = sum - distance. Centres from body_poses().
    rng = np.random.default_rng(5)
    n = 40
    with aqs.Linkage() as L:
        radii = rng.uniform(0.2, 0.7, n)
        for i in range(n):
            b = L.add_body(1.0, (0.5, 0, 0), [0.1, 0, 0, 0, 0.1, 0, 0, 0, 0.1])
            L.add_joint("revolute", i - 1, b, pos=(1.0 if i else 0.0, 0, 0), axis=(0, 0, 1))
            L.add_shape(b, "sphere", [radii[i]])
        L.finalize()
        for trial in range(5):
            L.set_positions(rng.uniform(-2.0, 2.0, n))
            centres = L.body_poses()[:, :3]
            expected = {}
            for a, b in itertools.combinations(range(n), 2):
                if b == a + 1:
                    continue  # joined: excluded by default
                d = np.linalg.norm(centres[a] - centres[b])
                if d < radii[a] + radii[b] - 1e-9:
                    expected[(a, b)] = radii[a] + radii[b] - d
            got = {(int(c["shape_a"]), int(c["shape_b"])): c["depth"] for c in L.collide()}
            assert set(got) == set(expected)
            for key, depth in expected.items():
                assert abs(got[key] - depth) < 1e-9
            stats = L.collision_stats()
            assert isinstance(stats, aqs.CollisionStats)
            assert stats._fields == ("nodes_refit", "volume_tests", "narrow_tests", "nodes_skipped",
                                     "certs_reused", "certs_made", "near_tests")
            assert stats.narrow_tests >= len(expected) and min(stats) >= 0


def test_obstacles_hulls_filters():
    with aqs.Linkage() as L:
        b = L.add_body(1.0, (0, 0, 0), [0.1, 0, 0, 0, 0.1, 0, 0, 0, 0.1])
        L.add_joint("prismatic", aqs.WORLD, b, axis=(0, 1, 0))
        cube = [[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)]
        assert L.add_hull(b, cube) == 0
        assert L.add_shape(aqs.WORLD, "box", [5, 0.5, 5], pos=(0, -0.9, 0)) == 1
        assert L.shape_count == 2
        L.finalize()
        c = L.collide()
        assert len(c) == 1 and c["body_a"][0] == b and c["body_b"][0] == aqs.WORLD
        assert abs(c["depth"][0] - 0.1) < 1e-9 and abs(c["ny"][0] + 1.0) < 1e-9
        L.set_collision_filter(aqs.WORLD, 2, 0xFFFFFFFF)
        L.set_collision_filter(b, 1, 1)
        assert len(L.collide()) == 0
        L.set_collision_filter(b, 1, 3)
        assert len(L.collide()) == 1
        L.exclude_collision(aqs.WORLD, b)
        assert not L.any_contact()


def test_errors_name_argument_and_leave_linkage_unchanged():
    with chain(3, 0.3, joined=False) as L:
        with pytest.raises(aqs.RangeError, match="body = 7"):
            L.add_shape(7, "sphere", [1.0])
        with pytest.raises(aqs.InvalidArgument, match=r"size\[0\] = nan"):
            L.add_shape(0, "sphere", [float("nan")])
        with pytest.raises(aqs.InvalidArgument, match=r"size\[1\] = -2"):
            L.add_shape(0, "capsule", [1.0, -2.0])
        with pytest.raises(aqs.InvalidArgument, match="coplanar"):
            L.add_hull(0, [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
        with pytest.raises(aqs.InvalidArgument, match=r"pos\[1\] = inf"):
            L.add_shape(0, "box", [1, 1, 1], pos=(0, float("inf"), 0))
        with pytest.raises(aqs.InvalidArgument, match="mode = 'fast'"):
            L.collide("fast")
        assert L.shape_count == 3
        assert len(L.collide()) == 0


def test_penalty_contact_rest_depth():
    # A pendulum (m = 1, centre of mass at 0.5) with a tip sphere comes to rest
    # on a box: k depth x = m g 0.5 cos q, so depth = m g 0.5 / k to within the
    # contact point's offset from the tip (2%).
    with aqs.Linkage() as L:
        b = L.add_body(1.0, (0.5, 0, 0), [0.01, 0, 0, 0, 0.01, 0, 0, 0, 0.01])
        L.add_joint("revolute", aqs.WORLD, b, axis=(0, 0, 1))
        L.add_shape(b, "sphere", [0.1], pos=(1, 0, 0))
        L.add_shape(aqs.WORLD, "box", [0.2, 0.5, 0.2], pos=(1, -0.6, 0))
        L.finalize()
        L.set_gravity((0, -9.81, 0))
        with pytest.raises(aqs.InvalidArgument, match="stiffness = -1"):
            L.set_contact_stiffness(-1)
        L.set_contact_stiffness(1e4)
        for _ in range(400):
            L.step(1e-5 ** 0.5)
        L.solve()
        assert abs(L.accelerations()[0]) < 1e-9
        c = L.collide()
        assert len(c) == 1
        assert abs(c["depth"][0] - 9.81 * 0.5 / 1e4) < 0.02 * 9.81 * 0.5 / 1e4
