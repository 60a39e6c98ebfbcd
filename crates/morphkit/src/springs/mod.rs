//! Physical blendshapes (Ma et al. 2012).
