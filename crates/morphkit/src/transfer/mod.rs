//! Animation transfer between different meshes (Wang & Lee 2008; Sumner & Popović 2004).
