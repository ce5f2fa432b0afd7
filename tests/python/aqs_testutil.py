"""Helpers of the pytest suite: the vector files, random cases, building a
linkage from a case, and an independent dense numpy solver (MATH.md section 2) that knows
nothing of aqs.

A "case" is a dict in the format of tests/vectors/exact/*.json (see
tests/vectors/README.md): bodies, joints, positions, gravity, body_forces,
joint_forces and optionally expected.
"""

import glob
import json
import os

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))


def vectors_dir():
    """$AQS_VECTORS, else the repository's own tests/vectors."""
    return os.environ.get("AQS_VECTORS") or os.path.join(REPO, "tests", "vectors")


def exact_vector_files():
    return sorted(glob.glob(os.path.join(vectors_dir(), "exact", "*.json")))


def load_case(path):
    with open(path) as handle:
        return json.load(handle)


def rel_err(got, expected, floor=0.0):
    """Relative 2-norm error over the whole array: |got - expected| / max(|expected|, floor).

    floor keeps an expected answer that is zero up to roundoff (a free fall's
    joint forces) from turning roundoff into a relative error of 1."""
    got = np.asarray(got, dtype=float).ravel()
    expected = np.asarray(expected, dtype=float).ravel()
    assert got.shape == expected.shape, (got.shape, expected.shape)
    scale = max(np.linalg.norm(expected), floor)
    diff = np.linalg.norm(got - expected)
    return diff / scale if scale > 0 else diff


# ---------------------------------------------------------------------------
# Random cases
# ---------------------------------------------------------------------------

ONE_DOF_OR_MORE = ["revolute", "prismatic", "spherical", "universal", "cylindrical", "planar"]


def random_quat(rng):
    q = rng.normal(size=4)
    return q / np.linalg.norm(q)


def random_position(kind, rng):
    if kind == "spherical":
        return list(random_quat(rng))
    if kind == "free":
        return list(rng.normal(size=3)) + list(random_quat(rng))
    return list(rng.normal(size={"revolute": 1, "prismatic": 1, "fixed": 0, "universal": 2,
                                 "cylindrical": 2, "planar": 3}[kind]))


def random_case(rng, kinds, tree=False, floating=False, mass_range=(0.5, 2.0), loads=True):
    """A case dict (vector format) with joint i from parent to body i."""
    n = len(kinds)
    bodies, joints, positions = [], [], []
    for i, kind in enumerate(kinds):
        p = rng.uniform(0.5, 1.0, size=3)
        R = quat_to_matrix(random_quat(rng))
        m = np.exp(rng.uniform(*np.log(mass_range)))
        bodies.append({"mass": m, "com": list(rng.normal(size=3) * 0.3),
                       "inertia": (m * R @ np.diag(p) @ R.T).tolist()})
        if i == 0:
            parent, kind = -1, ("free" if floating else kind)
        else:
            parent = int(rng.integers(0, i)) if tree else i - 1
        joints.append({"type": kind, "parent": parent, "child": i,
                       "pos": list(rng.normal(size=3) * 0.5), "quat": list(random_quat(rng)),
                       "axis": list(rng.normal(size=3))})
        positions += random_position(kind, rng)
    case = {"bodies": bodies, "joints": joints, "positions": positions,
            "gravity": list(rng.normal(size=3) * 5), "body_forces": [], "joint_forces": []}
    if loads:
        for i in rng.choice(n, size=max(1, n // 3), replace=False):
            case["body_forces"].append({"body": int(i), "force": list(rng.normal(size=3)),
                                        "point": list(rng.normal(size=3)),
                                        "torque": list(rng.normal(size=3))})
        for k, j in enumerate(joints):
            if NV[j["type"]] and j["type"] != "free":
                case["joint_forces"].append({"joint": k,
                                             "tau": list(rng.normal(size=NV[j["type"]]))})
    return case


def build(aqs, case, linkage=None):
    """Build (and finalize) a linkage from a case; set positions and loads."""
    L = linkage if linkage is not None else aqs.Linkage()
    # The vectors' inertias are synthetic: SPD, not always physically realizable.
    L.set_inertia_check(False)
    for b in case["bodies"]:
        L.add_body(b["mass"], b["com"], b["inertia"])
    for j in case["joints"]:
        L.add_joint(j["type"], j["parent"], j["child"], j.get("pos", (0, 0, 0)),
                    j.get("quat", (1, 0, 0, 0)), j.get("axis", (0, 0, 1)))
    L.finalize()
    apply_state(L, case)
    return L


def apply_state(L, case):
    L.set_positions(case["positions"])
    L.set_gravity(case.get("gravity", (0, 0, 0)))
    for load in case.get("body_forces", []):
        L.set_body_force(load["body"], load["force"], load.get("point"), load.get("torque"))
    for load in case.get("joint_forces", []):
        L.set_joint_force(load["joint"], load["tau"])


# ---------------------------------------------------------------------------
# Dense reference: joint-space mass matrix and generalized forces in the world
# frame, Cholesky solve; constraint forces by Newton-Euler on subtrees.
# ---------------------------------------------------------------------------

NQ = {"revolute": 1, "prismatic": 1, "spherical": 4, "free": 7, "fixed": 0,
      "universal": 2, "cylindrical": 2, "planar": 3}
NV = {"revolute": 1, "prismatic": 1, "spherical": 3, "free": 6, "fixed": 0,
      "universal": 2, "cylindrical": 2, "planar": 3}


def skew(p):
    return np.array([[0.0, -p[2], p[1]], [p[2], 0.0, -p[0]], [-p[1], p[0], 0.0]])


def quat_to_matrix(q):
    w, x, y, z = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def matrix_to_quat(R):
    """A unit quaternion (w, x, y, z) with w >= 0 for a rotation matrix."""
    K = np.array([
        [R[0, 0] - R[1, 1] - R[2, 2], R[1, 0] + R[0, 1], R[2, 0] + R[0, 2], R[2, 1] - R[1, 2]],
        [R[1, 0] + R[0, 1], R[1, 1] - R[0, 0] - R[2, 2], R[2, 1] + R[1, 2], R[0, 2] - R[2, 0]],
        [R[2, 0] + R[0, 2], R[2, 1] + R[1, 2], R[2, 2] - R[0, 0] - R[1, 1], R[1, 0] - R[0, 1]],
        [R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1], R[0, 0] + R[1, 1] + R[2, 2]],
    ]) / 3.0
    values, vectors = np.linalg.eigh(K)
    x, y, z, w = vectors[:, np.argmax(values)]
    q = np.array([w, x, y, z])
    return q if w >= 0 else -q


def axis_angle(a, angle):
    a = np.asarray(a, dtype=float)
    a = a / np.linalg.norm(a)
    K = skew(a)
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def second_directions(a):
    """u, v of aqs.h: e = the coordinate axis of the smallest |a_i| (first such)."""
    e = np.zeros(3)
    e[int(np.argmin(np.abs(a)))] = 1.0
    u = e - np.dot(e, a) * a
    u /= np.linalg.norm(u)
    return u, np.cross(a, u)


def joint_motion(kind, axis, q):
    """(R, t, S): the child frame in the joint frame, and the motion subspace
    (6 x nv) in the child frame about the child origin."""
    q = np.asarray(q, dtype=float)
    a = np.asarray(axis if axis is not None else (0, 0, 1), dtype=float)
    a = a / np.linalg.norm(a)
    zero = np.zeros(3)
    if kind == "revolute":
        return axis_angle(a, q[0]), zero, np.concatenate([a, zero])[:, None]
    if kind == "prismatic":
        return np.eye(3), q[0] * a, np.concatenate([zero, a])[:, None]
    if kind == "spherical":
        return quat_to_matrix(q), zero, np.vstack([np.eye(3), np.zeros((3, 3))])
    if kind == "free":
        return quat_to_matrix(q[3:7]), q[0:3].copy(), np.eye(6)
    if kind == "fixed":
        return np.eye(3), zero, np.zeros((6, 0))
    u, v = second_directions(a)
    if kind == "universal":
        R2 = axis_angle(u, q[1])
        S = np.zeros((6, 2))
        S[0:3, 0] = R2.T @ a
        S[0:3, 1] = u
        return axis_angle(a, q[0]) @ R2, zero, S
    if kind == "cylindrical":
        S = np.zeros((6, 2))
        S[0:3, 0] = a
        S[3:6, 1] = a
        return axis_angle(a, q[0]), q[1] * a, S
    if kind == "planar":
        R = axis_angle(a, q[2])
        S = np.zeros((6, 3))
        S[3:6, 0] = R.T @ u
        S[3:6, 1] = R.T @ v
        S[0:3, 2] = a
        return R, q[0] * u + q[1] * v, S
    raise ValueError(kind)


def motion_transform(R, p):
    """Motion vectors from a frame (orientation R, origin p) to its parent."""
    X = np.zeros((6, 6))
    X[0:3, 0:3] = R
    X[3:6, 0:3] = skew(p) @ R
    X[3:6, 3:6] = R
    return X


def spatial_inertia(mass, com, inertia):
    c = skew(com)
    I = np.zeros((6, 6))
    I[0:3, 0:3] = np.asarray(inertia, dtype=float).reshape(3, 3) + mass * c @ c.T
    I[0:3, 3:6] = mass * c
    I[3:6, 0:3] = mass * c.T
    I[3:6, 3:6] = mass * np.eye(3)
    return I


def body_poses(case):
    """World (R, p) of each body at the case's positions."""
    joints = case["joints"]
    nb = len(case["bodies"])
    q_offsets = np.cumsum([0] + [NQ[j["type"]] for j in joints])
    parent_joint = {j["child"]: k for k, j in enumerate(joints)}
    poses = [None] * nb

    def pose(body):
        if poses[body] is None:
            k = parent_joint[body]
            j = joints[k]
            if j["parent"] == -1:
                Rp, pp = np.eye(3), np.zeros(3)
            else:
                Rp, pp = pose(j["parent"])
            Rj = quat_to_matrix(j.get("quat", (1, 0, 0, 0)))
            pj = np.asarray(j.get("pos", (0, 0, 0)), dtype=float)
            q = np.asarray(case["positions"][q_offsets[k]:q_offsets[k + 1]], dtype=float)
            Rq, tq, _ = joint_motion(j["type"], j.get("axis"), q)
            poses[body] = (Rp @ Rj @ Rq, pp + Rp @ (pj + Rj @ tq))
        return poses[body]

    return [pose(i) for i in range(nb)]


def dense_solve(case):
    """(accelerations (nv), constraint_forces (joints x 6)) of a case."""
    joints = case["joints"]
    bodies = case["bodies"]
    nb, nj = len(bodies), len(joints)
    poses = body_poses(case)
    q_offsets = np.cumsum([0] + [NQ[j["type"]] for j in joints])
    v_offsets = np.cumsum([0] + [NV[j["type"]] for j in joints])
    nv = int(v_offsets[-1])
    parent_joint = {j["child"]: k for k, j in enumerate(joints)}
    X = [motion_transform(R, p) for R, p in poses]
    Xf = [np.linalg.inv(x).T for x in X]  # force transforms body -> world

    # World-frame motion subspace of each joint and the joints above each body.
    S_world = []
    for k, j in enumerate(joints):
        q = case["positions"][q_offsets[k]:q_offsets[k + 1]]
        _, _, S = joint_motion(j["type"], j.get("axis"), q)
        S_world.append(X[j["child"]] @ S)
    J = []
    for i in range(nb):
        Ji = np.zeros((6, nv))
        body = i
        while body != -1:
            k = parent_joint[body]
            Ji[:, v_offsets[k]:v_offsets[k + 1]] = S_world[k]
            body = joints[k]["parent"]
        J.append(Ji)

    I_world = []
    for i, b in enumerate(bodies):
        I_body = spatial_inertia(b["mass"], b["com"], b["inertia"])
        I_world.append(Xf[i] @ I_body @ Xf[i].T)

    g = np.zeros(6)
    g[3:6] = case.get("gravity", (0, 0, 0))
    f_ext = [np.zeros(6) for _ in range(nb)]
    for load in case.get("body_forces", []):
        i = load["body"]
        R, p = poses[i]
        F = np.asarray(load["force"], dtype=float)
        point = load.get("point")
        point = p + R @ np.asarray(point if point is not None else (0, 0, 0), dtype=float)
        torque = load.get("torque")
        torque = np.asarray(torque if torque is not None else (0, 0, 0), dtype=float)
        f_ext[i] += np.concatenate([torque + np.cross(point, F), F])
    Q = np.zeros(nv)
    for load in case.get("joint_forces", []):
        k = load["joint"]
        Q[v_offsets[k]:v_offsets[k + 1]] = np.atleast_1d(load["tau"])

    M = sum(J[i].T @ I_world[i] @ J[i] for i in range(nb))
    tau = Q + sum(J[i].T @ (f_ext[i] + I_world[i] @ g) for i in range(nb))
    qdd = np.linalg.solve(M, tau) if nv else np.zeros(0)

    residual = [I_world[i] @ (J[i] @ qdd) - f_ext[i] - I_world[i] @ g for i in range(nb)]
    children = {i: [] for i in range(-1, nb)}
    for j in joints:
        children[j["parent"]].append(j["child"])

    def subtree_sum(body):
        return residual[body] + sum((subtree_sum(c) for c in children[body]), np.zeros(6))

    forces = np.zeros((nj, 6))
    for k, j in enumerate(joints):
        forces[k] = X[j["child"]].T @ subtree_sum(j["child"])
    return qdd, forces
