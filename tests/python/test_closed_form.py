"""Cases with answers derived by hand (Newton/Euler), independent of any solver."""

import numpy as np
import pytest

import aqs
from aqs_testutil import axis_angle, quat_to_matrix

G = 9.81


def random_quat(rng):
    q = rng.normal(size=4)
    return q / np.linalg.norm(q)


def random_inertia(rng):
    """An SPD inertia obeying the triangle inequality: R diag(p) R^T."""
    p = rng.uniform(0.5, 1.0, size=3)
    R = quat_to_matrix(random_quat(rng))
    return R @ np.diag(p) @ R.T


@pytest.mark.parametrize("theta0", [0.0, 0.4])
@pytest.mark.parametrize("q", [0.0, 0.3, -1.2, np.pi / 2, 2.5])
def test_pendulum(q, theta0):
    """Revolute about z, gravity -y, com at (l,0,0): a compound pendulum.

    Gravity's moment about the pivot is c_w x (m g) with c_w = l (cos th,
    sin th, 0), th = theta0 + q, so n_z = -m g l cos th, and
    qdd = -m g l cos th / (I_zz + m l^2). The joint force on the body, in its
    frame about the pivot: m (a_com - g) = m (g sin th, qdd l + g cos th, 0),
    and no moment (I_c diagonal, so I_c alpha is along z, balanced with gravity).
    """
    m, l = 2.0, 0.7
    inertia = np.diag([0.01, 0.02, 0.03])
    half = 0.5 * theta0
    with aqs.Linkage() as L:
        b = L.add_body(m, (l, 0, 0), inertia)
        j = L.add_joint("revolute", aqs.WORLD, b, pos=(1.0, -2.0, 0.5),
                        quat=(np.cos(half), 0, 0, np.sin(half)), axis=(0, 0, 1))
        L.finalize()
        L.set_gravity((0, -G, 0))
        L.set_joint_position(j, q)
        L.solve()
        qdd = L.accelerations()
        force = L.joint_constraint_force(j)
    th = theta0 + q
    expected = -m * G * l * np.cos(th) / (inertia[2, 2] + m * l * l)
    np.testing.assert_allclose(qdd, [expected], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(force, [0, 0, 0, m * G * np.sin(th),
                                       m * (expected * l + G * np.cos(th)), 0],
                               rtol=0, atol=1e-11)


def test_pendulum_joint_torque_balances_gravity():
    """Holding torque tau = m g l cos q makes the acceleration zero."""
    m, l, q = 1.5, 0.4, 0.3
    with aqs.Linkage() as L:
        b = L.add_body(m, (l, 0, 0), np.diag([0.1, 0.1, 0.1]))
        L.add_joint("revolute", aqs.WORLD, b)
        L.finalize()
        L.set_gravity((0, -G, 0))
        L.set_positions([q])
        L.set_joint_force(0, m * G * l * np.cos(q))
        L.solve()
        assert abs(L.accelerations()[0]) < 1e-12


def test_pendulum_with_welded_mass():
    """A fixed joint welds a second body: the pendulum's inertia and moment add up."""
    m1, l1, m2, d = 1.0, 0.5, 3.0, 1.2
    I1, I2 = np.diag([0.01, 0.02, 0.03]), np.diag([0.04, 0.05, 0.06])
    q = 0.7
    with aqs.Linkage() as L:
        b1 = L.add_body(m1, (l1, 0, 0), I1)
        b2 = L.add_body(m2, (0, 0, 0), I2)
        L.add_joint("revolute", aqs.WORLD, b1)
        L.add_joint("fixed", b1, b2, pos=(d, 0, 0), axis=None)
        L.finalize()
        assert L.sizes() == (2, 2, 1, 1)
        L.set_gravity((0, -G, 0))
        L.set_positions([q])
        L.solve()
        qdd = L.accelerations()[0]
        pose, _ = L.body_pose(b2)
    expected = -G * (m1 * l1 + m2 * d) * np.cos(q) / (I1[2, 2] + m1 * l1 ** 2
                                                      + I2[2, 2] + m2 * d ** 2)
    assert qdd == pytest.approx(expected, rel=1e-12)
    np.testing.assert_allclose(pose, [d * np.cos(q), d * np.sin(q), 0], atol=1e-12)


def test_massless_body_welded_to_massive_body():
    m, l, q = 2.0, 0.3, -0.4
    inertia = np.diag([0.2, 0.3, 0.4])
    with aqs.Linkage() as L:
        b1 = L.add_body(m, (l, 0, 0), inertia)
        tip = L.add_body(0.0, (0, 0, 0), np.zeros((3, 3)))
        L.add_joint("revolute", aqs.WORLD, b1)
        L.add_joint("fixed", b1, tip, pos=(1.0, 0, 0), axis=None)
        L.finalize()
        L.set_gravity((0, -G, 0))
        L.set_positions([q])
        # A force of 1 N along world +y at the tip (1 m from the pivot along the rod).
        L.set_body_force(tip, (0, 1.0, 0))
        L.solve()
        qdd = L.accelerations()[0]
    expected = (-m * G * l * np.cos(q) + 1.0 * np.cos(q)) / (inertia[2, 2] + m * l * l)
    assert qdd == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("seed", range(4))
def test_prismatic_slider_under_gravity(seed):
    """A slider accelerates by the component of g along its world axis, plus tau/m;
    whatever its mass, com or inertia. The joint force has no component along
    the axis and balances the rest: f = I [0; qdd a - R^T g]."""
    rng = np.random.default_rng(seed)
    m = rng.uniform(0.5, 3.0)
    com = rng.normal(size=3)
    inertia = random_inertia(rng)
    quat = random_quat(rng)
    axis = rng.normal(size=3)
    g = rng.normal(size=3) * 5
    tau = rng.normal()
    with aqs.Linkage() as L:
        b = L.add_body(m, com, inertia)
        L.add_joint("prismatic", aqs.WORLD, b, pos=rng.normal(size=3), quat=quat, axis=axis)
        L.finalize()
        L.set_gravity(g)
        L.set_positions([rng.normal()])
        L.solve()
        free_fall = L.accelerations()[0]
        force = L.joint_constraint_force(0)
        L.set_joint_force(0, tau)
        L.solve()
        pushed = L.accelerations()[0]
    a = axis / np.linalg.norm(axis)
    R = quat_to_matrix(quat)
    assert free_fall == pytest.approx(np.dot(g, R @ a), rel=1e-12, abs=1e-12)
    assert pushed == pytest.approx(np.dot(g, R @ a) + tau / m, rel=1e-12, abs=1e-12)
    d = free_fall * a - R.T @ g
    expected = np.concatenate([m * np.cross(com, d), m * d])
    np.testing.assert_allclose(force, expected, rtol=0, atol=1e-11 * (1 + np.abs(expected).max()))
    assert abs(np.dot(force[3:], a)) < 1e-11 * (1 + np.abs(force).max())


@pytest.mark.parametrize("seed", range(4))
def test_free_body_pushed_off_centre(seed):
    """A floating body under gravity, a force F at a point r off its centre of
    mass and a pure torque T. Newton: a_c = F/m + g. Euler at zero velocity:
    I_w alpha = (r_w - c_w) x F + T with I_w = R I_c R^T. The body origin
    accelerates by a_o = a_c + alpha x (o - c_w). The joint reports
    [R^T alpha; R^T a_o] (body frame) and exerts no force."""
    rng = np.random.default_rng(100 + seed)
    m = rng.uniform(0.5, 3.0)
    com = rng.normal(size=3) * 0.3
    Ic = random_inertia(rng)
    p0, q0 = rng.normal(size=3), random_quat(rng)
    t, qb = rng.normal(size=3), random_quat(rng)
    F, r, T = rng.normal(size=3) * 3, rng.normal(size=3), rng.normal(size=3)
    g = np.array([0.0, 0.0, -G]) if seed % 2 else rng.normal(size=3)
    with aqs.Linkage() as L:
        b = L.add_body(m, com, Ic)
        L.add_joint("free", aqs.WORLD, b, pos=p0, quat=q0, axis=None)
        L.finalize()
        L.set_gravity(g)
        L.set_positions(np.concatenate([t, qb]))
        L.set_body_force(b, F, point=r, torque=T)
        L.solve()
        acc = L.accelerations()
        force = L.constraint_forces()
        pos, quat = L.body_pose(b)
    R0 = quat_to_matrix(q0)
    R = R0 @ quat_to_matrix(qb)
    o = p0 + R0 @ t
    c_w, r_w = o + R @ com, o + R @ r
    a_c = F / m + g
    alpha = np.linalg.solve(R @ Ic @ R.T, np.cross(r_w - c_w, F) + T)
    a_o = a_c + np.cross(alpha, o - c_w)
    expected = np.concatenate([R.T @ alpha, R.T @ a_o])
    np.testing.assert_allclose(acc, expected, rtol=0, atol=1e-10 * np.abs(expected).max())
    np.testing.assert_allclose(force, np.zeros((1, 6)), atol=1e-10 * np.abs(F).max())
    np.testing.assert_allclose(pos, o, atol=1e-12 * (1 + np.abs(o).max()))
    assert np.abs(quat_to_matrix(quat) - R).max() < 1e-12


def test_free_fall():
    """Gravity alone: the body's linear acceleration is g (in its own frame R^T g)."""
    g = np.array([1.0, -2.0, -9.0])
    quat = np.array([0.5, 0.5, -0.5, 0.5])
    with aqs.Linkage() as L:
        L.add_body(1.3, (0.1, 0.2, 0.3), np.diag([0.3, 0.4, 0.5]))
        L.add_joint("free", aqs.WORLD, 0, axis=None)
        L.finalize()
        L.set_gravity(g)
        L.set_positions([0, 0, 0, *quat])
        L.solve()
        acc = L.accelerations()
    np.testing.assert_allclose(acc, np.concatenate([np.zeros(3), quat_to_matrix(quat).T @ g]),
                               atol=1e-13)


def test_cylindrical_decoupled():
    """Cylindrical about z, com off the axis, gravity along -z: the rotation and the
    translation decouple (S1^T I S2 = (m c x z).z = 0)."""
    m, l = 2.0, 0.5
    inertia = np.diag([0.1, 0.2, 0.3])
    tau = (0.7, 1.1)
    with aqs.Linkage() as L:
        b = L.add_body(m, (l, 0, 0), inertia)
        L.add_joint("cylindrical", aqs.WORLD, b, axis=(0, 0, 1))
        L.finalize()
        L.set_gravity((0, 0, -G))
        L.set_positions([0.3, -0.2])
        L.set_joint_force(0, tau)
        L.solve()
        acc = L.accelerations()
    np.testing.assert_allclose(acc, [tau[0] / (inertia[2, 2] + m * l * l), -G + tau[1] / m],
                               rtol=1e-12)


def test_planar_decoupled():
    """Planar with a = z (so u = x, v = y), com at the body origin: translations
    and rotation decouple; gravity -y."""
    m = 1.7
    inertia = np.diag([0.1, 0.2, 0.3])
    tau = (0.4, -0.3, 0.25)
    with aqs.Linkage() as L:
        b = L.add_body(m, (0, 0, 0), inertia)
        L.add_joint("planar", aqs.WORLD, b, axis=(0, 0, 1))
        L.finalize()
        L.set_gravity((0, -G, 0))
        L.set_positions([0.5, -0.25, 1.0])
        L.set_joint_force(0, tau)
        L.solve()
        acc = L.accelerations()
        pos, _ = L.body_pose(b)
    np.testing.assert_allclose(acc, [tau[0] / m, -G + tau[1] / m, tau[2] / inertia[2, 2]],
                               rtol=1e-12)
    np.testing.assert_allclose(pos, [0.5, -0.25, 0], atol=1e-14)


def test_universal_at_zero():
    """Universal with a = z (u = x) at q = 0, com at (0, l, 0), gravity -z: the
    moment about the pivot is (-m g l, 0, 0), along u; M is diagonal here."""
    m, l = 1.2, 0.8
    inertia = np.diag([0.1, 0.2, 0.3])
    with aqs.Linkage() as L:
        b = L.add_body(m, (0, l, 0), inertia)
        L.add_joint("universal", aqs.WORLD, b, axis=(0, 0, 1))
        L.finalize()
        L.set_gravity((0, 0, -G))
        L.solve()
        acc = L.accelerations()
    np.testing.assert_allclose(acc, [0.0, -m * G * l / (inertia[0, 0] + m * l * l)],
                               rtol=1e-12, atol=1e-12)


def test_revolute_rotation_matches_axis_angle():
    """The child frame turns by q about the axis (URDF): check a body pose."""
    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    with aqs.Linkage() as L:
        b = L.add_body(1.0, (0, 0, 0), np.eye(3))
        L.add_joint("revolute", aqs.WORLD, b, pos=(1, 2, 3), axis=axis)
        L.finalize()
        L.set_positions([0.9])
        pos, quat = L.body_pose(b)
    np.testing.assert_allclose(pos, [1, 2, 3], atol=1e-14)
    np.testing.assert_allclose(quat_to_matrix(quat), axis_angle(axis, 0.9), atol=1e-13)


# (n, mass decades, tolerance). The tolerances leave room over what the DCA
# gives (MATH.md 3.8: it is intrinsically less accurate than a dense or
# recursive solve when chains are long or masses extreme); a textbook
# articulated-body recursion in numpy reaches 6e-13, 3e-11, 2e-11, 1e-9 here.
HARD_CHAINS = [(400, 0, 1e-8), (2000, 0, 1e-6), (200, 4, 1e-6), (200, 6, 1e-4)]


@pytest.mark.parametrize("n, decades, tol", HARD_CHAINS)
def test_long_prismatic_chain_falls_together(n, decades, tol):
    """n bodies on prismatic joints that all slide along the same world axis a:
    the whole chain falls as one, so the root joint accelerates by g.a and every
    other joint by 0, whatever the masses (here spread over `decades` decades),
    inertias and joint offsets."""
    rng = np.random.default_rng(n + decades)
    axis = np.array([1.0, -2.0, 0.5])
    a = axis / np.linalg.norm(axis)
    g = np.array([0.3, -9.81, 1.2])
    with aqs.Linkage() as L:
        parent = aqs.WORLD
        for i in range(n):
            m = 10.0 ** rng.uniform(-decades / 2, decades / 2)
            L.add_body(m, rng.normal(size=3), m * random_inertia(rng))
            L.add_joint("prismatic", parent, i, pos=rng.normal(size=3), axis=axis)
            parent = i
        L.finalize()
        L.set_gravity(g)
        L.set_positions(rng.normal(size=n))
        L.solve()
        acc = L.accelerations()
    expected = np.zeros(n)
    expected[0] = np.dot(g, a)
    assert np.linalg.norm(acc - expected) <= tol * abs(expected[0])
