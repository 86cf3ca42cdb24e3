#!/usr/bin/env python3
"""Rest AED of `run-dataset` results per group (standard vs non-standard proportions): unaligned,
and scaled about the feet to the reference height (as `eval`'s aed_rest_at_height), plus the
mean height ratio. Usage: scripts/aed_by_proportions.py DATASET RESULTS [RESULTS ...]"""
import json,struct,numpy as np,sys,glob,os
DS=sys.argv[1]
def mesh(s):
    b=open(DS+f'/{s}.mesh','rb').read(); V=struct.unpack_from('<I',b,12)[0]
    return np.frombuffer(b,dtype='<f4',count=V*3,offset=16).reshape(V,3).astype(float)
def obj(p): return np.array([[float(t) for t in l.split()[1:4]] for l in open(p) if l.startswith('v ')])
names=['legs','arms','shoulders','head','torso']
for res in sys.argv[2:]:
    acc={'standard':[], 'non-standard':[]}
    for p in sorted(glob.glob(DS+'/*.json')):
        s=os.path.basename(p)[:-5]
        if not s.isdigit(): continue
        g=json.load(open(p)); t=g['style']['proportions']
        grp='standard' if all(abs(t[n]-1)<1e-12 for n in names) else 'non-standard'
        r=mesh(s); e=obj(f'{res}/{s}_rest.obj'); h=g['height_m']; he=e[:,1].max()-e[:,1].min()
        aed=np.linalg.norm(r-e,axis=1).mean()/h
        es=(e-np.array([0,e[:,1].min(),0]))*(h/he)+np.array([0,r[:,1].min(),0])
        acc[grp].append((aed,np.linalg.norm(r-es,axis=1).mean()/h,he/h))
    for k,v in acc.items():
        v=np.array(v); print(res,'%-12s n %3d aed %.4f at height %.4f height ratio %.3f'%(k,len(v),v[:,0].mean(),v[:,1].mean(),v[:,2].mean()))
