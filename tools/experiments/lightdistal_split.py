import sys, random, numpy as np
import os; sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'bindings', 'python'))
import aqs
def build(mu, seed=1, nh=20, nl=20, form="sqrt", solver="aba"):
    L=aqs.Linkage()
    prev=aqs.WORLD
    for i in range(nh+nl):
        m=1000.0 if i<nh else mu
        b=L.add_body(m,(0.5,0,0),np.diag([0.01*m,0.1*m,0.1*m]))
        L.add_joint("revolute",prev,b,(1.0 if i else 0.0,0,0),axis=(0,1,0) if i%2 else (0,0,1))
        prev=b
    L.set_dca_form(form); L.finalize()
    rng=random.Random(seed)
    L.set_positions([rng.uniform(-1,1) for _ in range(nh+nl)])
    L.set_gravity((0,0,-9.81)); L.set_body_force(prev,(0,mu,0),point=(1,0,0))
    L.set_exact_solver(solver)
    L.solve(); return np.array(L.accelerations())
for mu in (1e-6, 1e-12):
  a=build(mu); d=build(mu,solver="dca"); p=build(mu,form="phi",solver="dca")
  print(mu, "rel2 sqrt %.1e phi %.1e"%(np.linalg.norm(d-a)/np.linalg.norm(a),np.linalg.norm(p-a)/np.linalg.norm(a)))
  print(" |a| heavy %.1e light %.1e"%(np.linalg.norm(a[:20]),np.linalg.norm(a[20:])))
  print(" err heavy %.1e light %.1e"%(np.linalg.norm((d-a)[:20]),np.linalg.norm((d-a)[20:])))
  print(" per joint rel err sqrt:", " ".join("%.0e"%(abs(d[i]-a[i])/abs(a[i])) for i in range(40)))
print("variants mu=1e-12: nh nl  sqrt  phi  (rel2 vs ABA, max over 5 seeds)")
for nh,nl in [(1,1),(1,2),(2,1),(2,2),(3,3),(20,1),(20,2),(1,20),(2,20),(20,20)]:
    es=[];ep=[]
    for seed in range(1,6):
        a=build(1e-12,seed,nh,nl); d=build(1e-12,seed,nh,nl,solver="dca"); p=build(1e-12,seed,nh,nl,form="phi",solver="dca")
        es.append(np.linalg.norm(d-a)/np.linalg.norm(a)); ep.append(np.linalg.norm(p-a)/np.linalg.norm(a))
    print(nh,nl,"%.1e %.1e"%(max(es),max(ep)))
