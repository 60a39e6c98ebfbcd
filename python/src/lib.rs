//! Python bindings of morphkit: a thin client of the library (no algorithm is written here).
//!
//! Arrays follow libigl's Python conventions (`V` `(n, 3) float64`, `F` `(m, 3)` integers);
//! library errors become the exceptions of `morphkit/_errors.py`; every solve releases the GIL.

mod args;
mod arrays;
mod bake;
mod blend;
mod blend_args;
mod dict;
mod errors;
mod io;
mod mesh;
mod metrics;
mod predictor;
mod rig_io;
mod scene;
mod stop;
mod synth;
mod transfer;
mod transfer_options;
mod weld;

use pyo3::prelude::*;

#[pymodule]
fn _morphkit(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(io::read, m)?)?;
    m.add_function(wrap_pyfunction!(io::write, m)?)?;
    m.add_function(wrap_pyfunction!(io::read_morphs, m)?)?;
    m.add_function(wrap_pyfunction!(io::write_morphs, m)?)?;
    m.add_function(wrap_pyfunction!(io::read_animation, m)?)?;
    m.add_function(wrap_pyfunction!(io::write_animation, m)?)?;
    m.add_function(wrap_pyfunction!(rig_io::read_rig, m)?)?;
    m.add_function(wrap_pyfunction!(rig_io::write_rig, m)?)?;
    m.add_function(wrap_pyfunction!(metrics::metrics, m)?)?;
    m.add_function(wrap_pyfunction!(metrics::continuity, m)?)?;
    m.add_function(wrap_pyfunction!(synth::flexibility, m)?)?;
    m.add_function(wrap_pyfunction!(synth::geodesic_distance, m)?)?;
    m.add_function(wrap_pyfunction!(synth::synthesize, m)?)?;
    m.add_function(wrap_pyfunction!(transfer_options::transfer_defaults, m)?)?;
    m.add_function(wrap_pyfunction!(transfer_options::rig_defaults, m)?)?;
    m.add_class::<synth::PyPartitions>()?;
    m.add_class::<blend::PyPhysicalBlend>()?;
    m.add_class::<bake::PyBakedRig>()?;
    m.add_class::<blend::PyPredictor>()?;
    m.add_class::<scene::PyObstacle>()?;
    m.add_class::<scene::PySceneBlend>()?;
    m.add_class::<transfer::PyCorrespondence>()?;
    m.add_class::<transfer::PyTransfer>()?;
    m.add_class::<transfer::PyRigTransfer>()?;
    Ok(())
}
