"""How dark a drone is against its surroundings: training vs test split vs the downscaled and faded copies (trains nothing).

    PYTHONPATH=. python results/learning_curve/drone_downscaled/contrast.py     # ~60 s; reads ../shared, data/runs

Every 5th labelled frame of the drone videos of each split. Depth = median of a ring around the box (half the longest
side wide) minus the darkest decile inside the box, in gray levels; contrast = depth / (ring std + 1). The copies:
seed set 0 (data/runs/ingest_drone_seed0), shrunk as downscaled_positives shrinks them, and faded as faded_positives
fades them (contrast c ~ log-U[0.3, 0.9] inside the feathered box; here applied to the whole frame).
"""
import json, numpy as np, cv2
from pathlib import Path
from synthaug.data.video import read_video_with_labels, find_video
from synthaug.data.seedset import SeedSet
sp=json.load(open('configs/splits/halmstad.json')); V=Path('../shared/data/halmstad/videos'); L=Path('../shared/data/halmstad/labels')
def contrast(frame, box):
    x,y,w,h=box; H,W=frame.shape; m=max(w,h)*0.5
    x0,y0,x1,y1=int(max(0,x-m)),int(max(0,y-m)),int(min(W,x+w+m)),int(min(H,y+h+m))
    reg=frame[y0:y1,x0:x1].astype(float); mask=np.zeros_like(reg,bool)
    mask[int(y-y0):int(y-y0+h), int(x-x0):int(x-x0+w)]=True
    if (~mask).sum()<10 or mask.sum()<4: return None
    ring=reg[~mask]; inside=reg[mask]
    return (np.median(ring)-np.percentile(inside,10))/ (ring.std()+1.0), abs(np.median(ring)-np.percentile(inside,10))
rows={}
for split in ('train','val','test'):
    out=[]
    for s in [v for v in sp[split] if sp['classes'].get(v)=='drone']:
        frames,labels,_=read_video_with_labels(find_video(V,s), L/f'{s}.json')
        for i in range(0,len(frames),5):
            b=labels.boxes[i]
            if b is None: continue
            b=np.asarray(b,float).reshape(-1,4)[0]; side=max(b[2],b[3])
            c=contrast(frames[i],b)
            if c: out.append((side,)+c)
    rows[split]=np.array(out)
ss=SeedSet.load('data/runs/ingest_drone_seed0/seedsets/drone_100'); rng=np.random.default_rng(0); d=[]
for i in range(len(ss)):
    f=ss.frame(i); b=np.asarray(ss.boxes[i],float).reshape(-1,4)[0]; Lr=max(b[2],b[3])
    if Lr<16: continue
    s=float(np.exp(rng.uniform(np.log(16),np.log(min(24,Lr))))); k=s/Lr
    sm=cv2.resize(f,(round(f.shape[1]*k),round(f.shape[0]*k)),interpolation=cv2.INTER_AREA)
    c=contrast(sm,b*k)
    if c: d.append((s,)+c)
rows['downscaled seeds (seed set 0)']=np.array(d)
# the faded copies (faded_positives' rule on the whole frame: inside the feathered box, frame - (1-c)(frame - background))
from scipy.ndimage import gaussian_filter
rng=np.random.default_rng(6); d=[]
for i in range(len(ss)):
    f=ss.frame(i).astype(float); bgf=ss.background_frame(i).astype(float); b=np.asarray(ss.boxes[i],float).reshape(-1,4)[0]
    m=np.zeros_like(f); m[int(round(b[1])):int(round(b[1]+b[3])), int(round(b[0])):int(round(b[0]+b[2]))]=1
    Lr=max(b[2],b[3]); m=gaussian_filter(m, Lr/28.0)  # 1 patch px of feathering (the box spans 0.7 x 40 = 28 patch px)
    c=float(np.exp(rng.uniform(np.log(0.3),np.log(0.9))))
    r=contrast(np.clip(f-(1-c)*m*(f-bgf),0,255),b)
    if r: d.append((Lr,)+r)
rows['faded seeds (seed set 0)']=np.array(d)
for k,a in rows.items():
    for lo,hi in ((0,24),(24,48)):
        sel=a[(a[:,0]>=lo)&(a[:,0]<hi)]
        if len(sel): print(f"{k:32s} {lo}-{hi}px n={len(sel):5d} contrast median {np.median(sel[:,1]):.2f} [q25 {np.percentile(sel[:,1],25):.2f}, q75 {np.percentile(sel[:,1],75):.2f}]  darkest-decile depth {np.median(sel[:,2]):.1f} gray levels")
