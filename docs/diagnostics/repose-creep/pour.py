import sys, numpy as np
d = np.loadtxt(sys.argv[1], delimiter=',', skiprows=1)
x,y,z,vx,vy,vz = d.T[:6]
sp=np.sqrt(vx**2+vy**2+vz**2)
print("in hopper", (y>0.6).sum(), "in stream", ((y>0.45)&(y<0.6)).sum(), "on base", ((y>0.25)&(y<0.55)&(x>0.8)&(x<1.6)).sum(), "troughs", ((x<0.8)|(x>1.6)).sum())
heap=(y>0.25)&(y<0.55)&(x>0.8)&(x<1.6)
print("heap top", y[heap].max(), "median speed heap mm/s", 1e3*np.median(sp[heap]), "p90", 1e3*np.percentile(sp[heap],90))
