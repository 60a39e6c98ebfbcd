//! The weld on the real ICT head (issue 54): 56 shells, whose borders lie on one another, vertex
//! on vertex. Only split seams weld; touching shells stay apart, so the welded rig has no edge
//! that three triangles share (coincidence alone made 110 such edges).

mod common;

use morphkit::io::read_shape_set;
use morphkit::mesh::{Weld, WELD_TOLERANCE};
use std::collections::HashMap;

#[test]
fn the_ict_weld_keeps_shells_apart_and_every_edge_manifold() {
    let Some(paths) = common::ict_rig_paths() else {
        return common::skip("the_ict_weld_keeps_shells_apart_and_every_edge_manifold");
    };
    let shapes = read_shape_set(&paths).unwrap();
    let w = Weld::of_shapes(&shapes, WELD_TOLERANCE);
    let mut uses: HashMap<(u32, u32), usize> = HashMap::new();
    for t in w.triangles(shapes.triangles()) {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *uses.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let over = uses.values().filter(|&&u| u > 2).count();
    let input_over = {
        let mut u: HashMap<(u32, u32), usize> = HashMap::new();
        for t in shapes.triangles() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *u.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        u.values().filter(|&&n| n > 2).count()
    };
    eprintln!(
        "ICT: {} vertices welded, {over} edges of 3+ triangles (input {input_over})",
        w.merged()
    );
    assert_eq!(over, input_over, "the weld made non-manifold edges");
    // The head's OBJ shares positions across its UV seams, so nothing here is an exporter's
    // split: the 369 vertices that coincidence alone welded all fused touching shells.
    assert_eq!(w.merged(), 0, "touching shells fused");
}
