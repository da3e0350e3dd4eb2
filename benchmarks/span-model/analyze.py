#!/usr/bin/env python3
"""The span model of the culler's CPU stages: how fast a frame could run on P workers, from one thread's timings.

With pool-replay.patch applied (a diagnostic build, never committed into the library), CULLIDE_POOL_SIM=16 makes
every TaskPool claim 16 workers (so chunk sizes and schedules are those of a 16-thread pool) but run every chunk on
the calling thread, timing each; CULLIDE_POOL_SIM_LOG=F writes the frames, the parallel calls (with their call
sites) and the chunks' microseconds to F. This script replays each call's chunks on P workers (each takes the next
chunk when free, as the pool's atomic counter hands them out), adds the serial time between calls, and prints the
predicted frame for P = 1 .. 16, the calls by their span at P = 16, and the longest serial steps. It leaves out
every cost of the threads themselves (waking, polling, memory traffic): a measured P-thread frame above the
prediction is that cost.

    git apply benchmarks/span-model/pool-replay.patch && cmake --build build --target cullide-bench-run
    CULLIDE_POOL_SIM=16 CULLIDE_POOL_SIM_LOG=/tmp/env3.log build/benchmarks/cullide-bench-run --scene env3 \
        --engine cullide-cpu --threads 16 --frames 100 --out /tmp/x.json
    python3 benchmarks/span-model/analyze.py /tmp/env3.log build/plugin/libcullide.so
    git apply -R benchmarks/span-model/pool-replay.patch
"""
import sys, subprocess, collections, heapq
log = sys.argv[1]; lib = sys.argv[2]
frames = []; cur = None; reg = None
for line in open(log):
    p = line.split()
    if p[0] == 'F': cur = {'t0': float(p[1]), 'regions': []}
    elif p[0] == 'G': cur['t1'] = float(p[1]); frames.append(cur); cur = None
    elif p[0] == 'R': reg = {'t0': float(p[1]), 'addr': p[2], 'chunks': []}
    elif p[0] == 'c': reg['chunks'].append(float(p[1]))
    elif p[0] == 'E':
        reg['t1'] = float(p[1])
        if cur is not None: cur['regions'].append(reg)
frames = frames[2:]  # skip warm-up
addrs = sorted({r['addr'] for f in frames for r in f['regions']})
names = {}
for a in addrs:
    # The call site: the innermost frames (inlined ones too) that are neither the standard library nor the pool.
    o = subprocess.run(['addr2line', '-i', '-f', '-C', '-s', '-e', lib, '0x%x' % (int(a, 16) - 1)],
                       capture_output=True, text=True).stdout.strip().split('\n')
    fr = [(o[i][:60], o[i + 1]) for i in range(0, len(o) - 1, 2)]
    keep = [f for f in fr if 'std::' not in f[0] and 'parallelFor' not in f[0]]
    names[a] = ' < '.join(x[0].split('(')[0][-40:] + '@' + x[1] for x in (keep or fr)[:2])
def makespan(chunks, P):
    w = [0.0]*P
    for c in chunks:
        t = heapq.heappop(w); heapq.heappush(w, t + c)
    return max(w)
Ps = [1, 2, 4, 8, 16]
tot = {P: 0.0 for P in Ps}; ser = 0.0; wall = 0.0; nreg = 0
per = collections.defaultdict(lambda: {P: 0.0 for P in Ps} | {'n': 0, 'chunks': 0})
for f in frames:
    T = f['t1'] - f['t0']; wall += T
    inreg = sum(r['t1'] - r['t0'] for r in f['regions'])
    ser += T - inreg; nreg += len(f['regions'])
    for r in f['regions']:
        d = per[r['addr']]; d['n'] += 1; d['chunks'] += len(r['chunks'])
        for P in Ps:
            m = makespan(r['chunks'], P); d[P] += m; tot[P] += m
n = len(frames)
print(f"frames {n}; wall/frame {wall/n/1000:.3f} ms; serial {ser/n/1000:.3f} ms; regions/frame {nreg/n:.1f}")
for P in Ps: print(f"  P={P:2d}: predicted {(ser+tot[P])/n/1000:.3f} ms (regions {tot[P]/n/1000:.3f})")
print("per region site (ms/frame at P=1, P=16; chunks/call):")
for a, d in sorted(per.items(), key=lambda kv: -kv[1][16]):
    chunks = d['chunks'] / max(1, d['n'])
    print(f"  {d[1]/n/1000:7.3f} {d[16]/n/1000:7.3f}  calls {d['n']/n:4.1f} chunks {chunks:7.1f}  {names[a]}")
# serial gaps: average per position in frame
gaps = collections.defaultdict(float)
for f in frames:
    prev_t, prev_site = f['t0'], 'FRAME-START'
    for r in f['regions']:
        gaps[(prev_site, r['addr'])] += r['t0'] - prev_t
        prev_t, prev_site = r['t1'], r['addr']
    gaps[(prev_site, 'FRAME-END')] += f['t1'] - prev_t
print("serial gaps (ms/frame):")
for (a, b), t in sorted(gaps.items(), key=lambda kv: -kv[1])[:8]:
    print(f"  {t/n/1000:.3f}  after {names.get(a,a)}  before {names.get(b,b)}")
