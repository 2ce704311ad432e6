//! Wavefront OBJ output of snow meshes: `<name>.obj` with one `o` per mesh (`v`, `vt`, `vn`,
//! `f v/vt/vn`), `<name>.mtl` with one material per mesh (snow white, or its texture as
//! `map_Kd` and its alpha as `map_d`), and `<name>_<mesh>.png` per texture. Coordinates are the
//! input's own axes and units (see [`SourceFrame`]); floats are written in Rust's shortest
//! round-trip form, so reading the file back gives the same f32 values. Every file is written
//! atomically, the OBJ last.

use super::{SnowObject, png_bytes};
use crate::MeshError;
use crate::scene::SourceFrame;
use snowscape_io::{AtomicWriteError, write_atomic, write_bytes_atomic};
use std::io::Write;
use std::path::Path;

/// Writes `meshes` to `path` (`.obj`) with its `.mtl` and texture PNGs beside it.
pub fn write_obj(path: &Path, meshes: &[SnowObject], frame: &SourceFrame) -> Result<(), MeshError> {
    let checked = meshes
        .iter()
        .map(SnowObject::checked)
        .collect::<Result<Vec<_>, _>>()?;
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "snow".into());
    let dir = path.parent().unwrap_or(Path::new(""));
    let names: Vec<String> = checked
        .iter()
        .enumerate()
        .map(|(i, m)| format!("{}_{i}", clean_name(&m.name)))
        .collect();
    let mut mtl = String::from("# snowscape snow materials\n");
    for (i, (m, name)) in checked.iter().zip(&names).enumerate() {
        let [r, g, b, _] = super::SNOW_BASE_COLOUR;
        mtl += &format!("\nnewmtl {name}\nKd {r} {g} {b}\nKs 0 0 0\nillum 1\n");
        if let (Some(img), Some(_)) = (&m.texture, &m.uvs) {
            let png_name = format!("{stem}_{i}.png");
            let png_path = dir.join(&png_name);
            write_bytes_atomic(&png_path, &png_bytes(img, &png_path)?)?;
            mtl += &format!("Kd 1 1 1\nmap_Kd {png_name}\nmap_d -imfchan m {png_name}\n");
        }
    }
    let mtl_name = format!("{stem}.mtl");
    write_bytes_atomic(&dir.join(&mtl_name), mtl.as_bytes())?;
    write_atomic(path, |w| -> Result<(), MeshError> {
        let io = |source| {
            MeshError::Write(AtomicWriteError::Write {
                path: path.to_path_buf(),
                source,
            })
        };
        writeln!(w, "# snowscape snow mesh\nmtllib {mtl_name}").map_err(io)?;
        let mut base = 1usize;
        for (m, name) in checked.iter().zip(&names) {
            writeln!(w, "o {name}\nusemtl {name}").map_err(io)?;
            for p in &m.positions {
                let [x, y, z] = frame.to_file(*p);
                writeln!(w, "v {x} {y} {z}").map_err(io)?;
            }
            if let Some(uvs) = &m.uvs {
                for [u, v] in uvs {
                    // OBJ's v runs up from the bottom of the image.
                    writeln!(w, "vt {u} {}", 1.0 - v).map_err(io)?;
                }
            }
            for n in m.normals() {
                let [x, y, z] = frame.direction_to_file(*n);
                writeln!(w, "vn {x} {y} {z}").map_err(io)?;
            }
            for t in &m.triangles {
                let [a, b, c] = t.map(|i| i as usize + base);
                match m.uvs {
                    Some(_) => writeln!(w, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}"),
                    None => writeln!(w, "f {a}//{a} {b}//{b} {c}//{c}"),
                }
                .map_err(io)?;
            }
            base += m.positions.len();
        }
        Ok(())
    })
}

/// A name usable after `o` and `newmtl`: no whitespace or control characters.
fn clean_name(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| {
            if c.is_whitespace() || c.is_control() {
                '_'
            } else {
                c
            }
        })
        .collect();
    if s.is_empty() { "snow".into() } else { s }
}
