import sys, os
__file__ = os.path.join(os.path.dirname(os.path.abspath(sys.argv[0])), 'lightdistal_split.py'); exec(open(__file__).read().split('for mu in')[0])
nh,nl=20,20
FORM="phi"
a=build(1e-12,1,nh,nl)
base=build(1e-12,1,nh,nl,solver="dca",form=FORM)
print("unperturbed %.1e"%(np.linalg.norm(base-a)/np.linalg.norm(a)))
nodes=[int(x) for x in sys.argv[1:]]
for n in nodes:
    out=[]
    for kind in (0,):
        e=0
        for sd in range(3):
            os.environ["AQS_PN"]=str(n); os.environ["AQS_PK"]=str(kind); os.environ["AQS_PS"]=str(sd)
            d=build(1e-12,1,nh,nl,solver="dca",form=FORM)
            e=max(e,np.linalg.norm(d-base)/np.linalg.norm(a))
        out.append(e)
    os.environ.pop("AQS_PN")
    print("node",n,"entry %.1e"%tuple(out))
