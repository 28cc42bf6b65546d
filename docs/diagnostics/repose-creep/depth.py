import sys, numpy as np
d = np.loadtxt(sys.argv[1], delimiter=',', skiprows=1)
x,y,z,vx,vy,vz = d.T[:6]
s = float(sys.argv[2]) if len(sys.argv)>2 else 0.01
on = (y>0.25)&(x>0.8)&(x<1.6)
x,y,z,vx,vy,vz = x[on],y[on],z[on],vx[on],vy[on],vz[on]
sp = np.sqrt(vx**2+vy**2+vz**2)
b = np.floor((x-0.8)/s).astype(int)
top = np.full(b.max()+1, -1.0)
for bi, yi in zip(b,y): top[bi] = max(top[bi], yi)
depth = np.round((top[b]-y)/s).astype(int)
print("n", len(x), "max speed", sp.max(), "at", x[sp.argmax()], y[sp.argmax()], "depth", depth[sp.argmax()])
for k in [0,1,2,3,4,6,8,10,15]:
    m = depth==k
    if m.sum(): print(f"depth {k}: n {m.sum()} median {1e3*np.median(sp[m]):.1f} mm/s p90 {1e3*np.percentile(sp[m],90):.1f} max {1e3*sp[m].max():.1f}  mean vx-sign-flow {1e3*np.median(np.abs(vx[m])):.1f}")
# speed by x for top layer
m = depth==0
for lo in np.arange(0.8,1.6,0.1):
    mm = m&(x>=lo)&(x<lo+0.1)
    if mm.sum(): print(f"x {lo:.1f}: top median {1e3*np.median(sp[mm]):.1f}, deep(>=6) median {1e3*np.median(sp[(depth>=6)&(x>=lo)&(x<lo+0.1)]) if ((depth>=6)&(x>=lo)&(x<lo+0.1)).sum() else float('nan'):.1f}")
