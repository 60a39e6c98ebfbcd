"""How far the interactive mode's space is from the full solve (issue 38): for the scrub bench's
twelve combinations (the same seeded states as `morphkit bench --suite scrub --steps 12`), the
best approximation of the full solve's correction x* - P(w) in the span of the snapshot
corrections the interactive mode would use (every active target at 1/4, 1/2, 3/4; every active
pair at (1/2, 1/2) and (0.3, 0.3)), as the largest vertex distance over the diagonal; then the
same span with extra columns, each the finite difference of two full solves:
  +sens      each active target s at 1/4, 1/2, 3/4 with another active target u at EPS
             (how s's equilibrium moves when u joins: a "tangent" column),
  +pairsens  each active pair at (1/2, 1/2) and (0.3, 0.3) with the third target at EPS,
  +both      both, and +trip  the three targets at 1/2 each (ICT only).
A least-squares fit: it says what the space can hold, not what the reduced solve finds.

    # with the Python module built and staged (python/tests/pytest.rs shows how):
    PYTHONPATH=STAGED python tools/interactive_span.py horse|ict [EPS] [DATA]

EPS defaults to 0.05; DATA to ../shared/data. Every solve is a canonical full solve, so the
ICT run takes about 50 minutes on one core. Results: docs/performance.md, "Night of
6 December".
"""
import sys, time, itertools, numpy as np, morphkit
M = (1 << 64) - 1
class Stream:
    def __init__(s, seed): s.x = seed
    def next(s):
        s.x = (s.x + 0x9e3779b97f4a7c15) & M
        z = s.x
        z = ((z ^ (z >> 30)) * 0xbf58476d1ce4e5b9) & M
        z = ((z ^ (z >> 27)) * 0x94d049bb133111eb) & M
        return z ^ (z >> 31)
    def uniform(s, lo, hi): return lo + (hi - lo) * (s.next() >> 11) / float(1 << 53)
    def distinct(s, n, k):
        out = []
        while len(out) < min(k, n):
            i = s.next() % n
            if i not in out: out.append(i)
        return out
def states(n, changes, face, seed=38):
    r = Stream(seed); out = []
    for _ in range(changes):
        w = [0.0]*n
        if face:
            for i in r.distinct(n, 3): w[i] = r.uniform(0.3, 1.0)
        else:
            ij = r.distinct(n, 2); a = r.uniform(0, 1); w[ij[0]] = a; w[ij[1]] = r.uniform(0, 1 - a)
        out.append(w)
    return out
rig = sys.argv[1]
D = (sys.argv[3] if len(sys.argv) > 3 else '../shared/data').rstrip('/') + '/'
if rig == 'ict':
    ex = ["browInnerUp_L","cheekPuff_L","eyeBlink_L","eyeBlink_R","jawLeft","jawOpen","mouthFunnel","mouthPucker","mouthSmile_L","mouthSmile_R"]
    base, F = morphkit.read(D+'ict-facekit/generic_neutral_mesh.obj.gz')
    T = [morphkit.read(D+f'ict-facekit/{e}.obj.gz')[0] for e in ex]
    face = True
else:
    base, F = morphkit.read(D+'sumner-horse-camel/horse-reference.obj.gz')
    T = [morphkit.read(D+f'sumner-horse-camel/horse-{i:02}.obj.gz')[0] for i in range(1, 11)]
    face = False
n = len(T)
diag = np.linalg.norm(base.max(0) - base.min(0))
t = time.time(); blend = morphkit.PhysicalBlend(base, T, F); print('build', time.time() - t, flush=True)
cache = {}
def solve(w):
    k = tuple(round(a, 12) for a in w)
    if k not in cache:
        x = np.asarray(blend.solve(list(w)))
        cache[k] = x - np.asarray(blend.predict(list(w)))
    return cache[k]
def W(pairs):
    w = [0.0]*n
    for s, a in pairs: w[s] = a
    return w
eps = float(sys.argv[2]) if len(sys.argv) > 2 else 0.05
def err(target, cols):
    A = np.stack([c.ravel() for c in cols], 1)
    y, *_ = np.linalg.lstsq(A, target.ravel(), rcond=1e-10)
    r = (target.ravel() - A @ y).reshape(-1, 3)
    return np.linalg.norm(r, axis=1).max() / diag
rows = []
for w in states(n, 12, face):
    act = [i for i in range(n) if w[i] != 0]
    tgt = solve(w)
    base_cols = [solve(W([(s, a)])) for s in act for a in (0.25, 0.5, 0.75)]
    base_cols += [solve(W([(s, a), (u, a)])) for s, u in itertools.combinations(act, 2) for a in (0.5, 0.3)]
    sens = []
    for s in act:
        for a in (0.25, 0.5, 0.75):
            for u in act:
                if u != s:
                    sens.append((solve(W([(s, a), (u, eps)])) - solve(W([(s, a)]))) / eps)
    psens = []
    for s, u in itertools.combinations(act, 2):
        for v in act:
            if v not in (s, u):
                for a in (0.5, 0.3):
                    psens.append((solve(W([(s, a), (u, a), (v, eps)])) - solve(W([(s, a), (u, a)]))) / eps)
    trip = [solve(W([(s, 0.5) for s in act]))] if len(act) == 3 else []
    e0 = err(tgt, base_cols); e1 = err(tgt, base_cols + sens); e2 = err(tgt, base_cols + psens); e3 = err(tgt, base_cols + sens + psens)
    e4 = err(tgt, base_cols + trip) if trip else float('nan')
    print(' '.join(f'{a:.2f}' for a in w), f'base {100*e0:.3f}% +sens {100*e1:.3f}% +pairsens {100*e2:.3f}% +both {100*e3:.3f}% +trip {100*e4:.3f}%  ncols {len(base_cols)}+{len(sens)}+{len(psens)}', flush=True)
    rows.append((e0, e1, e2, e3, e4))
R = np.array(rows) * 100
print('median', np.median(R, 0), 'max', R.max(0), 'within 0.1%', (R <= 0.1).sum(0))
