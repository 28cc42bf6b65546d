import sys, numpy as np
d = np.loadtxt(sys.argv[1], delimiter=',', skiprows=1)
x,y,z,vx,vy,vz,p,sxx,syy,szz,sxy,sxz,syz = d.T
alpha = np.sqrt(2)*np.tan(np.radians(30))
s=0.01
on = (y>0.25)&(x>0.8)&(x<1.6)
nrm = np.sqrt(sxx**2+syy**2+szz**2+2*(sxy**2+sxz**2+syz**2))
ratio = np.where(p>0, nrm/(alpha*np.maximum(p,1e-30)), np.inf)
sp = np.sqrt(vx**2+vy**2+vz**2)
b = np.floor((x-0.8)/s).astype(int)
top = {}
for bi, yi, o in zip(b,y,on):
    if o: top[bi] = max(top.get(bi,-1), yi)
depth = np.array([round((top.get(bi, yi)-yi)/s) for bi,yi in zip(b,y)])
R2 = ((sxx-syy)/2)**2 + sxy**2
parts = np.stack([2*R2, 1.5*szz**2, 2*sxz**2, 2*syz**2])/np.maximum(nrm**2,1e-30)
# wall layer: z index
zi = np.round((z-0.005)/s).astype(int)
print("heap particles", on.sum(), " p=0:", (on&(p<=0)).sum())
for name, m in [("all heap", on), ("at cone (ratio>0.98)", on&(ratio>0.98)), ("inside", on&(ratio<=0.98))]:
    if m.sum()==0: continue
    print(f"{name}: n {m.sum()} median speed {1e3*np.median(sp[m]):.1f} mm/s; share of |s|^2: in-plane {np.mean(parts[0][m]):.2f} szz {np.mean(parts[1][m]):.2f} sxz {np.mean(parts[2][m]):.2f} syz {np.mean(parts[3][m]):.2f}")
for k in [0,1,2,3,4,6,8,12,16]:
    m = on&(depth==k)
    if m.sum(): print(f"depth {k}: n {m.sum()} at-cone frac {np.mean(ratio[m]>0.98):.2f} median ratio {np.median(ratio[m]):.2f} p median {np.median(p[m]):.0f} Pa (lith {1000*9.81*s*(k+0.5):.0f}) in-plane share {np.mean(parts[0][m]):.2f} szz {np.mean(parts[1][m]):.2f} sxz+syz {np.mean(parts[2][m]+parts[3][m]):.2f}")
for zz in sorted(set(zi[on]))[:7]:
    m = on&(zi==zz)
    print(f"z layer {zz}: n {m.sum()} at-cone {np.mean(ratio[m]>0.98):.2f}, sxz+syz share {np.mean(parts[2][m]+parts[3][m]):.2f}, median speed {1e3*np.median(sp[m]):.1f}")
# slope frame on the flanks (beta from the measured angle, right flank descends to +x)
beta = np.radians(float(sys.argv[2])) if len(sys.argv)>2 else np.radians(22)
apex_x = 1.2
for side, sgn in [("left", 1), ("right", -1)]:
    m = on & ((x<apex_x-0.1) if sgn==1 else (x>apex_x+0.1)) & (depth>=1) & (depth<=8) & (p>0)
    b = sgn*beta
    N1 = (sxx-syy)/2; 
    tau = -N1*np.sin(2*b) + sxy*np.cos(2*b)   # shear on the slope-parallel plane
    N1s = N1*np.cos(2*b) + sxy*np.sin(2*b)
    R = np.sqrt(N1**2+sxy**2)
    print(f"{side}: n {m.sum()} median |tau_slope|/p {np.median(np.abs(tau[m])/p[m]):.3f}  median |N1_slope|/p {np.median(np.abs(N1s[m])/p[m]):.3f} median R/p {np.median(R[m]/p[m]):.3f}  (tan theta {np.tan(np.radians(30)):.3f}, tan beta {np.tan(beta):.3f}) median ||s||/p {np.median(nrm[m]/p[m]):.3f} alpha {alpha:.3f}")
