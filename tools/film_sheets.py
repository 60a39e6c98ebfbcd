"""Film-scale test sheets (issue 38): an n x n grid of unit side as OBJ, flat, bent 60 degrees
in its plane into an annulus sector, and rolled 90 degrees about the y axis while waves of 2 %
of its side grow on it.

    python tools/film_sheets.py 1000 /tmp/film   # flat1000.obj, bent1000.obj, roll1000.obj
"""
import numpy as np, sys
n = int(sys.argv[1]); out = sys.argv[2]
u = np.linspace(0, 1, n)
X, Y = np.meshgrid(u, u, indexing="ij")
idx = np.arange(n*n).reshape(n, n)
a = idx[:-1, :-1].ravel(); b = idx[1:, :-1].ravel(); c = idx[1:, 1:].ravel(); d = idx[:-1, 1:].ravel()
tris = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)]) + 1
def write(path, P):
    with open(path, "w") as f:
        np.savetxt(f, P, fmt="v %.9f %.9f %.9f")
        np.savetxt(f, tris, fmt="f %d %d %d")
flat = np.stack([X.ravel(), Y.ravel(), np.zeros(n*n)], 1)
write(f"{out}/flat{n}.obj", flat)
ang = np.pi/3; R = 1/ang
th = (X - 0.5) * ang; r = R + (Y - 0.5)
bent = np.stack([r.ravel()*np.sin(th.ravel()), r.ravel()*np.cos(th.ravel()) - R, np.zeros(n*n)], 1)
write(f"{out}/bent{n}.obj", bent)
# rolled 90 degrees about the y axis into an arc, with waves that grow
ang = np.pi/2; R = 1/ang
th = (X - 0.5) * ang
w = 0.02*np.sin(6*np.pi*X)*np.sin(6*np.pi*Y)
rr = R + w
roll = np.stack([rr.ravel()*np.sin(th.ravel()), Y.ravel(), R - rr.ravel()*np.cos(th.ravel())], 1)
write(f"{out}/roll{n}.obj", roll)
