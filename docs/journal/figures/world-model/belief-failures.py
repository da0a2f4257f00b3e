"""Why a run failed the largest belief error: reads logs of runs made with
RUST_LOG=info,twin::belief=trace,twin=debug,carto=debug (colours stripped), one per run, in the
folder given, and for each finds the largest error, walks back to where the error was last under
2 cm, and calls it a wrong fix (a range correction of 3 cm or more in between), a touch (a
contact logged in between) or drift (neither). Journal, world-model, round 14."""
import re,sys,glob,collections
res=collections.Counter()
for f in sorted(glob.glob(sys.argv[1] + '/*.log')):
    lines=open(f).read().split('\n')
    samples=[]
    for i,l in enumerate(lines):
        if 'belief against' in l:
            d=dict(re.findall(r'(\w+)=(\S+)',l))
            samples.append((i,float(d['t_s']),float(d['error']),float(d['heading_error']),float(d['e_across']),float(d['e_along'])))
    if not samples: continue
    k=max(range(len(samples)),key=lambda j:samples[j][2])
    i,T,E,H,_,_=samples[k]
    j=k
    while j>0 and samples[j][2]>0.02: j-=1
    i0,t0=samples[j][0],samples[j][1]
    seg=lines[i0:i+1]
    fw=sum(1 for x in seg if 'SendMoveCartography { command: Forward' in x)
    big=[re.search(r'innovation: (\S+) ',x).group(1) for x in seg if ('range at rest' in x or 'range looking' in x) and 'Applied' in x and abs(float(re.search(r'innovation: (\S+) ',x).group(1)))>0.03]
    touch=sum(1 for x in seg if re.search(r'touch|contact|bump|push|stall',x,re.I) and 'twin' in x)
    hs=[s[3] for s in samples if t0<=s[1]<=T]
    kind='wrong-fix' if big else ('touch' if touch else 'drift')
    res[kind]+=1
    print(f"{f.split('/')[-1]:20s} max {E:.3f}@{T:7.1f} from {t0:7.1f} ({T-t0:5.0f}s, {fw:3d} fwd) hd@max {H:.2f} hdmean {sum(hs)/len(hs):.2f} bigfix {big[:3]} touchlines {touch} -> {kind}")
print(res)
