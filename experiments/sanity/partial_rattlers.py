"""Usage: python3 partial_rattlers.py OUT_DIR (a `jamkit run` output of the
nmer family with packings written; uses the `spheres` rows).

Isostaticity margin with 'partial rattlers': bodies whose contacts all lie
on one sphere count D coordinates (their rotation is a zero mode) and need
D+1 contacts; other bodies count f and need f+1. Iterated to a fixed point."""
import json,sys,glob,math
def pairs(p):
    d=p['dim']; L=p['box']; S=p['spheres']; out=[]
    for a in range(len(S)):
        for b in range(a+1,len(S)):
            s,t=S[a],S[b]; bi,bj=int(s[d+1]),int(t[d+1])
            if bi==bj: continue
            r2=sum(((t[k]-s[k])-L[k]*round((t[k]-s[k])/L[k]))**2 for k in range(d))
            if math.sqrt(r2)-s[d]-t[d]<0: out.append((bi,bj,a,b))
    return out
for f in sorted(glob.glob(sys.argv[1]+'/packings/*.json')):
    p=json.load(open(f)); d=p['dim']; n=p['particles']; f_=3 if d==2 else 5
    C=pairs(p); alive=[True]*n
    while True:
        cnt=[0]*n; sph=[set() for _ in range(n)]
        for bi,bj,a,b in C:
            if alive[bi] and alive[bj]:
                cnt[bi]+=1;cnt[bj]+=1;sph[bi].add(a);sph[bj].add(b)
        kind=['r']*n; changed=False
        for i in range(n):
            if not alive[i]: continue
            if len(sph[i])>=2 and cnt[i]>=f_+1: kind[i]='f'
            elif cnt[i]>=d+1: kind[i]='p'
            else: alive[i]=False; changed=True
        if not changed: break
    nc=sum(1 for bi,bj,a,b in C if alive[bi] and alive[bj])
    nf=kind.count('f'); npart=kind.count('p')
    m=p['measures']
    margin=nc-(f_*nf+d*npart-d)
    print(f"{f.split('/')[-1]:34s} phi {p['phi']:.6f} z {m['z_j']:.4f} margin {m['iso_margin']:3d} | partial {npart} rattlers {n-nf-npart} Nc' {nc} margin' {margin:3d} z'(all non-rattlers) {2*nc/(nf+npart):.4f} escapes {m.get('saddle_escapes')} fire {m['fire_steps']} wall {m['wall_s']:.2f}")
