//! The hinges' exact Hessian in closed form (kept apart from the term's energy and
//! gradient: the second-order part alone is a page of derivatives).
use super::*;

impl HingeTerm {
    /// The full Hessian $2w(J^\top J + \sum_i \rho_i \nabla^2 \rho_i)$ of every hinge, in
    /// closed form. Near an equilibrium where the hinges balance the springs, $\rho \neq 0$
    /// and the Gauss–Newton part alone makes Newton converge only linearly; with the
    /// second-order part it converges quadratically.
    ///
    /// The second-order part is the Hessian of $f = r \cdot \rho$ with $r = \rho$ held fixed.
    /// In the edge variables $e = b - a$, $u_1 = c - a$, $u_2 = d - a$ (so $n_1 = e \times u_1$,
    /// $n_2 = u_2 \times e$),
    /// $$f = \beta_2^{-1}\, r\cdot(u_2 \times e) - \beta_1^{-1}\cos\bar\Theta\; r\cdot(e \times u_1) -
    ///   \beta_1^{-1}\sin\bar\Theta\; \hat e \cdot (n_1 \times r).$$
    /// A triple product $r\cdot(p \times q)$ has the constant mixed blocks
    /// $\partial^2/\partial p\,\partial q = -[r]_\times$ (and its transpose). The last term adds
    /// the curvature of $\hat e = e/\lVert e\rVert$: with $m = n_1 \times r$ and $\mu = m\cdot\hat e$,
    /// $\lVert e\rVert^2\, \nabla^2(m\cdot\hat e) = 3\mu\,\hat e\hat e^\top - \mu I - m\hat e^\top -
    /// \hat e m^\top$, and the products of first derivatives of $\hat e$ and $m$. The blocks are
    /// mapped to the corners by $e = b - a$, $u_1 = c - a$, $u_2 = d - a$. The tests check it
    /// against differences of the analytic gradient.
    pub(super) fn add_exact_hessian(&self, p: &TermParameters, x: &[f64], h: &mut BlockHessian) {
        let slots = self.slots.get(h);
        for (k, (&hv, q)) in self.hinges.iter().zip(p.values.chunks_exact(4)).enumerate() {
            let geometry = Geometry::new(q, hv.map(|v| p3(x, v)));
            let hy = Self::second_order(&geometry, &geometry.rho().into());
            let sl = slots.map(|s| &s[6 * k..6 * k + 6]);
            let rows = geometry.jacobian_rows();
            add_block_pairs(None, (h, sl), hv, &rows, &hy, 2.0 * self.weight[k]);
        }
    }

    /// The second-order blocks $H_y$ of one hinge in the edge variables (see
    /// [`Self::add_exact_hessian`]), for residual `r` at its `geometry`.
    pub(super) fn second_order(geometry: &Geometry, r: &Vector3<f64>) -> [[Matrix3<f64>; 3]; 3] {
        let id = Matrix3::<f64>::identity();
        // d enters only through u2 = d − a, whose blocks are constant.
        let [cs, sn, ib1, ib2] = geometry.q;
        let (e, u1) = (Vector3::from(geometry.e), Vector3::from(geometry.u1));
        let le = geometry.le;
        let eh = Vector3::from(geometry.eh);
        let n1 = Vector3::from(geometry.n1);
        // Second derivatives in (e, u1, u2): hy[p][q] = ∂²f/∂p∂q.
        let mut hy = [[Matrix3::<f64>::zeros(); 3]; 3];
        let (sr, ss) = (skew(r), skew(&r.cross(&eh)));
        // ib2 r·(u2 × e)
        hy[2][0] -= sr * ib2;
        hy[0][2] += sr * ib2;
        // −ib1 cs r·(e × u1)
        hy[0][1] += sr * (ib1 * cs);
        hy[1][0] -= sr * (ib1 * cs);
        // −ib1 sn ê·m, m = n1 × r. On an edge of zero length ê is undefined; there n1 = 0,
        // so m = 0 and these blocks vanish in the limit: they are left out where they are
        // not finite.
        let m = n1.cross(r);
        let me = m.dot(&eh);
        let mut g = [[Matrix3::<f64>::zeros(); 3]; 3];
        g[0][0] =
            (eh * eh.transpose() * (3.0 * me) - id * me - m * eh.transpose() - eh * m.transpose())
                / (le * le);
        let de = (id - eh * eh.transpose()) / le;
        let dm_e = sr * skew(&u1);
        let dm_u1 = -sr * skew(&e);
        g[0][0] += de.transpose() * dm_e + dm_e.transpose() * de;
        g[0][1] += de.transpose() * dm_u1 - ss;
        g[1][0] += dm_u1.transpose() * de + ss;
        if g.iter().flatten().all(|b| b.iter().all(|v| v.is_finite())) {
            for pp in 0..2 {
                for qq in 0..2 {
                    hy[pp][qq] -= g[pp][qq] * (ib1 * sn);
                }
            }
        }
        hy
    }
}
