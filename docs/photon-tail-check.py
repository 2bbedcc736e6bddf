# Double-precision Monte Carlo check of the tail of the single-term unbiased photon estimator
# (docs/PHOTON-MAPPING.md): one gather point, Poisson photons (mean 20 within r_1), cone kernel,
# power-law levels alpha = 2/3. Prints z P(|Z| > z), predicted (4/9) L, and the sample mean.
# Run: python3 docs/photon-tail-check.py (about a minute).
import random, math
random.seed(1)
a=2/3; r1=1.0; mean_n=20.0; rho=mean_n/(math.pi*r1*r1); L=rho
def W(d,r): return 3*(1-d/r)/(math.pi*r*r) if d<r else 0.0
def poisson(lam):
    l=math.exp(-lam); k=0; p=1.0
    while True:
        p*=random.random()
        if p<l: return k
        k+=1
N=200000; zs=[]
for s in range(N):
    n=poisson(mean_n)
    ds=[r1*math.sqrt(random.random()) for _ in range(n)]
    v=1-random.random()
    j=math.floor(v**(1/(a-1)))
    rj=r1*j**((a-1)/2); rj1=r1*(j+1)**((a-1)/2)
    p=j**(a-1)-(j+1)**(a-1)
    K1=sum(W(d,r1) for d in ds)
    D=sum(W(d,rj1)-W(d,rj) for d in ds)
    zs.append(K1+D/p)
zs.sort(key=abs)
for z in [1e2,1e3,1e4,1e5]:
    c=sum(1 for x in zs if abs(x)>z)/N
    pos=sum(1 for x in zs if x>z)/N
    print(f"z={z:g} P(|Z|>z)*z={c*z:.3f} (pred {4/9*L:.3f}) positive share {pos/max(c,1e-12):.2f}")
med=sorted(zs)[N//2]; print("median",med,"L",L, "mean", sum(zs)/N)
