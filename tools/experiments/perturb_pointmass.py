import sys, os, random, numpy as np
import os; sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'bindings', 'python'))
import aqs
def build(k, seed=1, form="sqrt", solver="aba"):
    L=aqs.Linkage(); prev=aqs.WORLD
    if k < 1e-8: L.set_inertia_check(False)
    for i in range(6):
        if i==2: b=L.add_body(0.75,(0.5,0,0),np.eye(3)*k)
        else: b=L.add_body(1.0,(0.5,0,0),np.diag([0.01,0.1,0.1]))
        L.add_joint("revolute",prev,b,(1.0 if i else 0.0,0,0),axis=(0,1,0) if i%2 else (0,0,1)); prev=b
    L.set_dca_form(form); L.finalize()
    rng=random.Random(seed); L.set_positions([rng.uniform(-1,1) for _ in range(6)])
    L.set_gravity((0,0,-9.81)); L.set_body_force(prev,(0.3,1,0.5),point=(1,0,0))
    L.set_exact_solver(solver); L.solve(); return np.array(L.accelerations())
k=1e-12
a=build(k); s=build(k,solver="dca"); p=build(k,form="phi",solver="dca")
print("k=%g sqrt %.1e phi %.1e"%(k,np.linalg.norm(s-a)/np.linalg.norm(a),np.linalg.norm(p-a)/np.linalg.norm(a)))
print("per joint sqrt:", " ".join("%.0e"%(abs(s[i]-a[i])/np.linalg.norm(a)) for i in range(6)))
for form in ("sqrt","phi"):
  for n in (2,5,6,10,11,12):
    out=[]
    for kind in ((0,1,3,4,5) if form=="sqrt" else (0,)):
        e=0
        for sd in range(3):
            os.environ.update(AQS_PN=str(n),AQS_PK=str(kind),AQS_PS=str(sd))
            d=build(k,form=form,solver="dca"); os.environ.pop("AQS_PN")
            base=build(k,form=form,solver="dca")
            e=max(e,np.linalg.norm(d-base)/np.linalg.norm(a))
        out.append("%.1e"%e)
    print(form,"node",n," ".join(out))
