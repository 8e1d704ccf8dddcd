#!/usr/bin/env python3
"""Relative focal error from a filter run's residual log, by two-view geometry with the gyro's rotation (prototype of
session 35; docs/diagnose.md, "A focal error from two views and the gyro").

Each pair of consecutive observations of a track: the camera rotation between them from the raw gyro (less the
filter's gyro bias from the calibration log, at the images' IMU-clock times t_cam + t̂_d), the point at the filter's
inverse depth times a per-track factor, a translation per image pair; the observation in the second image predicted
exactly (x' = π(R^T(P - t))) after mapping the measured coordinates through a focal error ε (x_true =
undist(dist(x_m)/(1 + ε))) and back. For each ε on a grid the depths and translations are fitted (Gauss-Newton
alternation, Huber weights) and ε-hat is the minimum of the weighted cost (parabola through the grid's three lowest).
Usage: focal_two_view.py RUN_DIR... (each with res.csv, res_calib.csv and the dataset in data/, as
scripts/experiments/diagnose_sizing.sh leaves them). Needs numpy and PyYAML (/usr/bin/python3 on Debian).
"""
import numpy as np, csv, sys, yaml
def skew(w): return np.array([[0,-w[2],w[1]],[w[2],0,-w[0]],[-w[1],w[0],0]])
def expm(w):
    th=np.linalg.norm(w); K=skew(w)
    if th<1e-12: return np.eye(3)+K
    return np.eye(3)+np.sin(th)/th*K+(1-np.cos(th))/th**2*K@K
def load(d):
    cam=yaml.safe_load(open(d+'/data/mav0/cam0/sensor.yaml').read().replace('%YAML:1.0',''))
    T=np.array(cam['T_BS']['data']).reshape(4,4); R_BC=T[:3,:3]
    k=cam['distortion_coefficients']
    imu=np.loadtxt(d+'/data/mav0/imu0/data.csv',delimiter=',',comments='#')
    rows=[]
    with open(d+'/res.csv') as f:
        for r in csv.DictReader(f):
            if r['status'] not in ('0','1'): continue
            x=float(r['x_norm']); y=float(r['y_norm'])
            if not np.isfinite(x): continue
            rows.append((int(r['feature_id']),int(r['t_cam_ns']),x,y,float(r['depth_m']),float(r['td_s'])))
    cal=list(csv.DictReader(open(d+'/res_calib.csv')))
    ct=np.array([int(c['t_cam_ns']) for c in cal]); bg=np.array([[float(c['b_g_%d'%i]) for i in range(3)] for c in cal])
    return R_BC,k,imu,rows,ct,bg
def distort(x,k):
    k1,k2,p1,p2=k; r2=(x**2).sum(1); rad=1+k1*r2+k2*r2**2
    xd=x[:,0]*rad+2*p1*x[:,0]*x[:,1]+p2*(r2+2*x[:,0]**2)
    yd=x[:,1]*rad+p1*(r2+2*x[:,1]**2)+2*p2*x[:,0]*x[:,1]
    return np.column_stack([xd,yd])
def undistort(xd,k):
    x=xd.copy()
    for _ in range(30):
        e=distort(x,k)-xd; x=x-e
    return x
def prepare(d):
    R_BC,k,imu,rows,ct,bg=load(d)
    rows.sort(key=lambda r:(r[0],r[1]))
    ti=imu[:,0]
    pairs=[]  # (track, t0, t1, x0, x1, depth0, R_C)
    Rcache={}
    def R_body(t0,t1,b):
        key=(t0,t1)
        if key in Rcache: return Rcache[key]
        R=np.eye(3); n=max(1,int((t1-t0)/1e6)); dt=(t1-t0)/n
        for j in range(n):
            tm=t0+(j+0.5)*dt
            i=min(max(np.searchsorted(ti,tm)-1,0),len(ti)-2); u=(tm-ti[i])/(ti[i+1]-ti[i])
            w=(1-u)*imu[i,1:4]+u*imu[i+1,1:4]-b
            R=R@expm(w*dt*1e-9)
        Rcache[key]=R; return R
    for a,b in zip(rows[:-1],rows[1:]):
        if a[0]!=b[0]: continue
        if not (40e6<b[1]-a[1]<60e6): continue
        t0=a[1]+a[5]*1e9; t1=b[1]+b[5]*1e9
        ci=min(np.searchsorted(ct,a[1]),len(ct)-1)
        Rb=R_body(t0,t1,bg[ci])
        RC=R_BC.T@Rb@R_BC
        pairs.append((a[0],a[1],np.array(a[2:4]),np.array(b[2:4]),a[4],RC))
    return pairs,k
def solve(pairs,k,eps,iters=10,huber=True):
    n=len(pairs)
    X0=np.array([p[2] for p in pairs]); X1=np.array([p[3] for p in pairs])
    X0t=undistort(distort(X0,k)/(1+eps),k)
    RC=np.array([p[5] for p in pairs])
    q=np.einsum('nji,nj->ni',RC,np.column_stack([X0t,np.ones(n)]))  # R^T x^h
    tid=np.array([p[0] for p in pairs]); fid=np.array([p[1] for p in pairs])
    ut,tinv=np.unique(tid,return_inverse=True); uf,finv=np.unique(fid,return_inverse=True)
    dep=np.array([p[4] for p in pairs])
    ok=np.isfinite(dep)&(dep>0)
    rho0=np.where(ok,1/np.where(ok,dep,1),0.3)   # the filter's inverse depth per observation
    rho=np.ones(len(ut))                         # per-track factor on it
    U=np.zeros((len(uf),3))
    w=np.ones(n)
    def model():
        rr=rho[tinv]*rho0; uu=U[finv]
        D=q[:,2]-rr*uu[:,2]
        xp=(q[:,:2]-rr[:,None]*uu[:,:2])/D[:,None]
        pm=undistort(distort(xp,k)*(1+eps),k)
        return rr,uu,D,xp,X1-pm
    for it in range(iters):
        rr,uu,D,xp,e=model()
        Ju=np.zeros((n,2,3)); Ju[:,0,0]=-rr/D; Ju[:,1,1]=-rr/D; Ju[:,:,2]=(rr/D)[:,None]*xp
        Ju*=(1+eps)
        # e ≈ e0 - Ju du  -> du = (Ju^T W Ju)^-1 Ju^T W e
        AtA=np.zeros((len(uf),3,3)); Atr=np.zeros((len(uf),3))
        np.add.at(AtA,finv,w[:,None,None]*np.einsum('nki,nkj->nij',Ju,Ju))
        np.add.at(Atr,finv,w[:,None]*np.einsum('nki,nk->ni',Ju,e))
        U=U+np.linalg.solve(AtA+1e-12*np.eye(3),Atr)
        rr,uu,D,xp,e=model()
        Jr=((-uu[:,:2]+xp*uu[:,2:3])/D[:,None])*(1+eps)*rho0[:,None]
        num=np.zeros(len(ut)); den=np.zeros(len(ut))
        np.add.at(num,tinv,w*np.einsum('nk,nk->n',Jr,e)); np.add.at(den,tinv,w*np.einsum('nk,nk->n',Jr,Jr))
        rho=rho+np.where(den>0,num/np.maximum(den,1e-30),0)
        rr,uu,D,xp,e=model()
        if huber:
            en=np.linalg.norm(e,axis=1); sc=1.4826*np.median(en)
            w=np.where(en<=3*sc,1.0,3*sc/np.maximum(en,1e-30))
    rr,uu,D,xp,e=model()
    return np.sum(w*np.sum(e**2,1)), np.sum(w)
if __name__=='__main__':
    for d in sys.argv[1:]:
        pairs,k=prepare(d)
        grid=np.arange(-0.01,0.0251,0.0025)
        J=[solve(pairs,k,e)[0] for e in grid]
        i=int(np.argmin(J)); i=min(max(i,1),len(grid)-2)
        a,b,c=J[i-1],J[i],J[i+1]; h=grid[1]-grid[0]
        emin=grid[i]+h*(a-c)/(2*(a-2*b+c))
        print(f"{d}: {len(pairs)} observation pairs, relative focal error {100 * emin:.3f} %", flush=True)
