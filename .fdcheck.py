import numpy as np, pinocchio as pin, pkdyn, time
for name in ["delta","gough_stewart"]:
    r=pkdyn.load(name); cs=r.closure_set; m=r.model; d=r.data
    rng=np.random.default_rng(0)
    for t in range(2):
        q=pin.integrate(m, r.q_home, rng.normal(size=m.nv)*0.3)
        _,J=cs.residual_and_jacobian(d,q)
        Jfd=np.zeros_like(J); h=1e-6
        for k in range(m.nv):
            e=np.zeros(m.nv); e[k]=h
            Jfd[:,k]=(cs.residual(d,pin.integrate(m,q,e))-cs.residual(d,pin.integrate(m,q,-e)))/(2*h)
        print(name, np.abs(J-Jfd).max())
r=pkdyn.load("gough_stewart")
from pkdyn.closed_form import gough_stewart as cf
pose=np.array([0.02,-0.01,r.params.home_height()+0.03,0.05,-0.04,0.1])
rho=cf.leg_lengths_rpy(r.params.a, r.params.b, pose)
q=r.q_home; ts=[]
for k in range(300):
  t=time.perf_counter(); fk=pkdyn.forward_geometry(r, rho[0]+1e-3*np.sin(k), q_init=q); ts.append(time.perf_counter()-t); q=fk.q
print('fk median us', np.median(ts)*1e6, fk.iterations)
t=time.perf_counter()
for k in range(500): r.closure_set.residual_and_jacobian(r.data,q)
print('eval us', (time.perf_counter()-t)/500*1e6)
