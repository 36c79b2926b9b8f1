//! Section 3 of the report: scaling with triangles, pixels and lights.

use std::fmt::Write as _;

use super::fmt::*;
use super::verdict::*;
use crate::schema::*;

/// Section 3: the plot and the triangle, pixel and light tables.
pub fn section(o: &mut String, r: &Results) {
    let sc = &r.scaling;
    let _ = writeln!(o, "## 3. Scaling\n");
    let _ = writeln!(o, "![scaling](scaling.png)\n");
    let _ = writeln!(
        o,
        "**Triangles.** The bunny replaced by a procedural bumpy sphere (a latitude/longitude grid, radius modulated by sines, vertex normals; about the bunny's size and place) from 10³ to 10⁶ triangles, 1024×1024, BVH. Frames: 5 (3 from 300,000 triangles up), after a warm-up frame.\n"
    );
    let _ = writeln!(
        o,
        "| Triangles | Render ms/frame, median [min–max] | Mrays/s | BVH build | Layout + upload | BVH records | Depth | BVH memory | Bytes/triangle |\n|---|---|---|---|---|---|---|---|---|"
    );
    for t in &sc.triangles {
        let _ = writeln!(
            o,
            "| {} | {} | {:.1} | {:.1} ms | {:.1} ms | {} | {} | {} | {:.1} |",
            int(t.triangles as u64),
            st(&t.render_ms),
            t.rays as f64 / t.render_ms.median / 1e3,
            t.bvh_build_ms,
            t.upload_ms,
            int(t.bvh_nodes as u64),
            t.bvh_depth,
            mib(t.bvh_bytes),
            t.bvh_bytes as f64 / t.triangles as f64
        );
    }
    if let (Some(first), Some(last)) = (sc.triangles.first(), sc.triangles.last()) {
        let build = last.build_ms();
        let _ = writeln!(
            o,
            "\nFrom {} to {} triangles ({:.0}× more) the frame time grows {:.2}× — roughly logarithmic, as a BVH should. The {}-triangle BVH builds in {} against {:.1} ms for one 1024×1024 frame of it (medians): the build takes {:.2}× a frame, {}; the whole host side (layout, build, upload) takes {:.0} ms. (This part ran while other processes used {:.2} cores on average: see the last table.)\n",
            int(first.triangles as u64),
            int(last.triangles as u64),
            last.triangles as f64 / first.triangles as f64,
            last.render_ms.median / first.render_ms.median,
            int(last.triangles as u64),
            match &last.bvh_rebuild_ms {
                Some(b) => format!(
                    "{:.0} ms [{:.0}–{:.0}] ({} builds: the one before its frames, the rest on fresh layouts after them)",
                    b.median,
                    b.min,
                    b.max,
                    b.samples.len()
                ),
                None => format!("{:.0} ms", last.bvh_build_ms),
            },
            last.render_ms.median,
            build / last.render_ms.median,
            build_clause(build_met(build, last.render_ms.median)),
            last.bvh_build_ms + last.upload_ms,
            r.parts
                .iter()
                .find(|p| p.part == "scaling")
                .map_or(f64::NAN, |p| p.other_cores)
        );
    }
    let _ = writeln!(
        o,
        "**Pixels.** The bunny scene rendered at smaller sizes from one upload (same field of view); 5 frames each.\n"
    );
    let _ = writeln!(
        o,
        "| Image | Pixels | Render ms/frame, median [min–max] | ns per pixel | Mrays/s |\n|---|---|---|---|---|"
    );
    for p in &sc.pixels {
        let px = p.width as f64 * p.height as f64;
        let _ = writeln!(
            o,
            "| {}×{} | {} | {} | {:.0} | {:.1} |",
            p.width,
            p.height,
            int(px as u64),
            st(&p.render_ms),
            p.render_ms.median * 1e6 / px,
            p.rays as f64 / p.render_ms.median / 1e3
        );
    }
    let _ = writeln!(
        o,
        "\n**Lights.** The bunny scene with its directional light and copies of it turned about the vertical axis (each 1/n of the intensity), 1024×1024; 5 frames each. Each light adds a shadow ray for every lit hit.\n"
    );
    let _ = writeln!(
        o,
        "| Lights | Rays per frame | Render ms/frame, median [min–max] | Mrays/s |\n|---|---|---|---|"
    );
    for l in &sc.lights {
        let _ = writeln!(
            o,
            "| {} | {} | {} | {:.1} |",
            l.lights,
            int(l.rays),
            st(&l.render_ms),
            l.rays as f64 / l.render_ms.median / 1e3
        );
    }
    let _ = writeln!(o);
}
