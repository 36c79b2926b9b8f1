//! Section 4 of the report: kernel specialisation.

use std::fmt::Write as _;

use super::fmt::*;
use crate::schema::*;

/// Section 4: compile phases and frames of the three kernels.
pub fn section(o: &mut String, r: &Results) {
    let sp = &r.specialise;
    let _ = writeln!(o, "## 4. Specialisation\n");
    let _ = writeln!(
        o,
        "The bunny scene with the kernel specialised to its features (triangles, vertex normals, one directional light, Phong: every other `override` false, so lavapipe's compiler drops that code) against the general kernel (`KernelOptions {{ specialise: false }}`: every feature override true, the same scene data). Compile figures: two cold compiles each (Mesa's cache disabled), in alternating order; frames: {} interleaved pairs at {}×{}. The third row specialises by writing the feature values into the WGSL text as `const`s before naga parses it (`KernelOptions {{ text_specialise: true }}`), the alternative to `override`s.\n",
        sp.frames.ratio.samples.len(),
        sp.frames.width,
        sp.frames.height
    );
    let _ = writeln!(
        o,
        "| Kernel | SPIR-V | naga | Pipeline creation | Driver compile (cold) | Render ms/frame, median [min–max] |\n|---|---|---|---|---|---|"
    );
    for (name, c, frames) in [
        ("general", &sp.general, &sp.frames.a_ms),
        ("specialised (overrides)", &sp.specialised, &sp.frames.b_ms),
        ("specialised (WGSL text)", &sp.text, &sp.text_frames.a_ms),
    ] {
        let _ = writeln!(
            o,
            "| {} | {} bytes | {} ms | {} ms | {} ms | {} |",
            name,
            int(c.spirv_bytes as u64),
            list(&c.naga_ms),
            list(&c.pipeline_ms),
            list(&c.driver_compile_ms),
            st(frames)
        );
    }
    let _ = writeln!(
        o,
        "\nGeneral / specialised per frame (per interleaved pair): **{}**.\n",
        ratio(&sp.frames.ratio)
    );
    if !sp.text_frames.ratio.samples.is_empty() {
        let _ = writeln!(
            o,
            "Specialised by WGSL text / by overrides per frame (per interleaved pair): **{}**. naga keeps constant-condition branches in both cases (the SPIR-V sizes above), so both leave the dead code to lavapipe's compiler, which removes it.\n",
            ratio(&sp.text_frames.ratio)
        );
    }
    if !sp.sampling.ratio.samples.is_empty() {
        let _ = writeln!(
            o,
            "The sampling overhead: scenes/showcase.json ({}×{}, no area light, 1 spp) with the area-light sampling code compiled in (`KernelOptions {{ with_sampling: true }}`) against the default kernel, which leaves it out: {} against {} ms/frame; with / without per interleaved pair: **{}**.\n",
            sp.sampling.width,
            sp.sampling.height,
            st(&sp.sampling.a_ms),
            st(&sp.sampling.b_ms),
            ratio(&sp.sampling.ratio)
        );
    }
}
