//! The report's textures section: what texturing and a cut-out cost.

use std::fmt::Write as _;

use super::fmt::*;
use crate::schema::*;

/// The textures section (absent from reports of runs that did not measure
/// it).
pub fn section(o: &mut String, r: &Results) {
    let Some(t) = &r.textures else {
        return;
    };
    let _ = writeln!(o, "## Textures\n");
    let _ = writeln!(
        o,
        "The bunny scene textured by `tools/measure/common/meshes.rs::textured_bunny_scene`: the bunny with cylindrical texture coordinates and a 256² texture, the ground tiling a 512² texture 16 times, both trilinear with ray-cone level of detail ({:.2} MiB of textures with their mip-maps). The masked variant makes the bunny's material a cut-out (alpha mask from the texture's stripes), which compiles the alpha test into traversal for camera and shadow rays. Interleaved frames in one process.\n",
        t.texture_bytes as f64 / 1048576.0
    );
    pair_table(o, &t.texturing);
    pair_table(o, &t.mask);
}
