//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

/// A mesh of the shared real-data folder; panics (fails the test) when it is missing, because
/// these tests exist to check the readers on real files.
pub fn mesh_path(name: &str) -> PathBuf {
    let p = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/meshes"
    ))
    .join(name);
    assert!(
        p.is_file(),
        "{} is missing: the mesh tests need ../shared/data beside the checkout",
        p.display()
    );
    p
}
