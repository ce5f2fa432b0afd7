"""A three-link pendulum settling under gravity, quasi-statically.

Three rods of length 1 m hang from revolute joints about z; gravity is -y.
Released horizontally, each step moves q by dt^2 * qdd with the velocity
reset to zero, so the chain creeps down towards hanging straight (q0 = -pi/2).

Run from the checkout after `make lib`:
    PYTHONPATH=bindings/python python3 bindings/python/examples/pendulum.py
"""

import math

import numpy as np

import aqs

LINKS, LENGTH, MASS = 3, 1.0, 1.0
# A thin rod about its centre: m l^2 / 12 across it, a little along it.
ROD_INERTIA = np.diag([1e-3, MASS * LENGTH ** 2 / 12, MASS * LENGTH ** 2 / 12])

with aqs.Linkage() as linkage:
    parent = aqs.WORLD
    for i in range(LINKS):
        body = linkage.add_body(MASS, com=(LENGTH / 2, 0, 0), inertia=ROD_INERTIA)
        pivot = (0, 0, 0) if parent == aqs.WORLD else (LENGTH, 0, 0)
        linkage.add_joint("revolute", parent, body, pos=pivot, axis=(0, 0, 1))
        parent = body
    linkage.finalize()
    linkage.set_gravity((0, -9.81, 0))
    print("libaqs %s, %s" % (aqs.version(), linkage))
    print("assembly tree:", linkage.tree_stats())

    linkage.solve()
    qdd = linkage.accelerations()
    print("initial joint accelerations (rad/s^2):", np.round(qdd, 4))

    dt = 0.01
    for step in range(1, 4001):
        linkage.step(dt)
        if step % 1000 == 0:
            q = linkage.positions()
            tip, _ = linkage.body_pose(LINKS - 1)
            print("step %4d  q = %s  last link origin at %s"
                  % (step, np.round(q, 4), np.round(tip, 3)))

    q = linkage.positions()
    print("first joint angle %.4f rad (hanging: %.4f)" % (q[0], -math.pi / 2))
