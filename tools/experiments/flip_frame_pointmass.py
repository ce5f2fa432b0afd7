# Which node's update loses the point-mass chain's digits: node n's relative rigid mode is
# formed once in the frame at the more mobile side's centre of mass (the default) and once
# at the other side's (AQS_FN=n, flip_frame.patch): mathematically the same, so the change
# in the answer is the rounding of that node's update.
import sys, os
__file__ = os.path.join(os.path.dirname(os.path.abspath(sys.argv[0])), 'perturb_pointmass.py')
exec(open(__file__).read().split('k=1e-12')[0])
for k in (1e-8, 1e-12, 1e-16):
    for seed in (1, 2, 3):
        a = build(k, seed); base = build(k, seed, solver="dca")
        row = []
        for n in (2, 5, 6, 10, 11, 12):
            os.environ["AQS_FN"] = str(n)
            d = build(k, seed, solver="dca")
            os.environ.pop("AQS_FN")
            row.append("%d:%.0e" % (n, np.linalg.norm(d - base) / np.linalg.norm(a)))
        print("k=%g seed %d: error %.1e; change when node n flips: %s" % (k, seed, np.linalg.norm(base - a) / np.linalg.norm(a), " ".join(row)))
