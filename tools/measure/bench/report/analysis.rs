//! The report's "what stands in the way": why penumbra on lavapipe is as
//! fast as it is, numbered points computed from this run's profile, CPU
//! port, peers and knobs.

use super::peers;
use crate::schema::Results;

/// The report's "what stands in the way" section, from this run's figures:
/// numbered points, each from one function.
pub fn markdown(r: &Results) -> String {
    [
        kernel_time(r),
        divergence(r),
        cost_per_iteration(r),
        next_steps(r),
        knobs(r),
    ]
    .concat()
}

/// Point 1: where the profile puts the time (the kernel, not the driver).
fn kernel_time(r: &Results) -> String {
    let jit = r
        .profile
        .dsos
        .iter()
        .find(|d| d.0.starts_with("[JIT]"))
        .map_or(f64::NAN, |d| d.1);
    let llvm: f64 = r
        .profile
        .dsos
        .iter()
        .filter(|d| d.0.contains("LLVM"))
        .map(|d| d.1)
        .sum();
    format!(

        "1. **The time is in the kernel itself.** The per-frame figure excludes compilation, and {}: the rest of lavapipe (dispatch, thread pool, copies) is small, so closing the gap means making the JIT-compiled traversal loop faster, not the driver around it.\n",
        if r.profile.skipped.is_none() {
            format!("in the profile above {jit:.0}% of all samples are in lavapipe's JIT-compiled kernel and {llvm:.0}% in LLVM compiling it (a one-off, cold)")
        } else {
            "no profile was taken in this run".to_string()
        }
    )
}

/// Point 2: the SIMD-8 utilisation of the traversal, from the CPU port's
/// replay.
fn divergence(r: &Results) -> String {
    let cpu = &r.cpu;
    let u = cpu.simd8_utilisation;
    format!(

        "2. **Divergence.** lavapipe runs the 8×8 workgroup as SIMD groups of 8 invocations (a row of 8 pixels, one per 32-bit lane of a 256-bit register); a loop iterates until the slowest lane is done. Replaying the traversal on the CPU with the same tree (`CpuScene::traversal_steps`, the CPU port's order: node visits plus triangle tests, {:.1} per pixel on average for the primary and shadow ray together) gives a SIMD-8 utilisation of **{:.0}%**: {:.0}% of lane-iterations are idle lanes waiting for the slowest ray of their group, so the 8-wide kernel does at most {:.1} scalar traversals' worth of work per iteration.\n",
        cpu.mean_steps,
        u * 100.0,
        (1.0 - u) * 100.0,
        8.0 * u
    )
}

/// Point 3: the cost of one 8-wide iteration against a scalar one, why, and
/// the kernel changes measured ([`KEPT`], [`TRIED`]).
fn cost_per_iteration(r: &Results) -> String {
    let cpu = &r.cpu;
    let u = cpu.simd8_utilisation;
    format!(

        "3. **Cost per lane-iteration.** The plain Rust port (same tree and traversal, at its best: see above) on the same {} threads takes {:.1} ms; lavapipe takes {:.1} ms ({:.2}×). Had each SIMD-8 iteration cost what one scalar iteration costs, lavapipe would be {:.1}× faster than the port; it is {:.2}× slower instead, so one 8-wide iteration of the generated code costs about {:.0}× a scalar iteration of rustc's code. Why, from the machine code lavapipe generates (dumped from a running process and read next to a `perf` profile): Mesa 25.0 loads storage-buffer data at a per-lane address as a loop over the 8 lanes — test the lane's mask bit, then for each 32-bit component bounds-check the offset, branch, load a scalar, insert it — with no gather instruction (the LLVM IR that `GALLIVM_DEBUG=ir MESA_SHADER_CACHE_DISABLE=true penumbra render scenes/bunny_scene.glb` prints shows it), and it takes its one-load path only for addresses that are uniform *and* outside any loop or branch, so every triangle and shader-table load of the traversal pays that loop (one more load per triangle test costs 1.7% of the frame). A load from a read-only storage image (`textureLoad` of a `texture_storage_2d<rgba32uint, read>`) is instead one call into a straight-line function: 8 lanes' 16-byte loads and a transpose, bounds handled by selects; so the BVH records and the triangles are texels, two and three each (`src/vulkan/image.rs`, `shaders/texels.wgsl`). (A sampled image's fetch, `texture_2d<u32>`, goes through the same kind of function but computes a mip level per lane: 8 scalar loads of level sizes and offsets, which ate most of the gain — read from the sample function's machine code, dumped with gdb next to a `perf` profile in which it took a fifth of the kernel's time.) The per-lane traversal stack becomes the same kind of scalar stores and loads, so its newest four entries live in a `vec4` register and only older ones in the array; and every branch inside a loop adds mask bookkeeping. Measured with `cargo run --release -p penumbra-tools --bin ab -- scenes/bunny_scene.glb --a A/shaders --b B/shaders --cpu-time` (interleaved frames of two shader trees, A and B unpacked with `git archive COMMIT shaders`; `--cpu-time` compares the CPU time of lavapipe's threads, which other processes on the cores do not inflate) or, where the host's data layout changed too, `tools/measure/ab_commits.sh A B 7` (the same with two builds): {}. Tried and not kept: {}.\n",
        cpu.threads,
        cpu.cpu_ms.median,
        cpu.gpu_ms.median,
        cpu.gpu_ms.median / cpu.cpu_ms.median,
        8.0 * u,
        cpu.gpu_ms.median / cpu.cpu_ms.median,
        8.0 * u * cpu.gpu_ms.median / cpu.cpu_ms.median,
        KEPT.join("; "),
        tried()
    )
}

/// Point 4: the peers' advantage and the likely next steps.
fn next_steps(r: &Results) -> String {
    let u = r.cpu.simd8_utilisation;
    format!(

        "{} The likely next steps: a wider BVH (four quantised children per record: about half the traversal steps, each with two more texel fetches and two more box tests — a fetch is a call to a function of about 40 instructions, which took 8.3% of a `perf` profile of a running `ab` against 36% for the kernel that calls it), and fewer loads per triangle test (three texel loads and the primitive reference, a storage-buffer load per lane; storing triangles in leaf order would drop the reference, which measured about 2% when the triangles were a storage buffer too). Packet traversal, which the peers use, would need lavapipe to load a subgroup-uniform node once; Mesa 25.0 does not (the {:.0}% utilisation above is not the limit).\n",
        peers::advantage(r),
        u * 100.0
    )
}

/// Point 5: lavapipe's knobs, where the run measured the vector widths.
fn knobs(r: &Results) -> String {
    let mut o = String::new();
    let knob = |name: &str, value: &str| {
        r.knobs
            .iter()
            .find(|k| k.env.iter().any(|(n, v)| n == name && v == value))
    };
    if let (Some(w128), Some(w512)) = (
        knob("LP_NATIVE_VECTOR_WIDTH", "128"),
        knob("LP_NATIVE_VECTOR_WIDTH", "512"),
    ) {
        o.push_str(&format!(
            "5. **lavapipe's knobs** (section 5) do not close the gap: 128-bit vectors (4 lanes) run at {:.2}× the default speed and 512-bit (16 lanes, AVX-512) at {:.2}×; {}\n",
            w128.speedup_vs_default.median,
            w512.speedup_vs_default.median,
            match knob("LP_NUM_THREADS", "1") {
                Some(t1) => format!(
                    "one thread instead of two runs at {:.2}× (≈ 0.5 would mean perfect use of the second core; more means the second core was partly taken by other processes).",
                    t1.speedup_vs_default.median
                ),
                None => String::new(),
            }
        ));
    }
    o
}

/// The kernel changes kept, each with the commits compared and the ratio
/// `ab --cpu-time` or `tools/measure/ab_commits.sh` measured (B/A of frame time).
const KEPT: &[&str] = &[
    "a `workgroupBarrier` for the ray counters made lavapipe run the whole kernel as coroutines — summing per subgroup instead, 52fe479 → 3079c47, gave 0.86× the frame time",
    "the closest-hit traversal descends every lane to a leaf before any lane tests triangles (Aila and Laine's while-while), 3079c47 → 1fbf176, 0.96×",
    "shadow rays visit the nearer child first and the slab test compares and selects instead of NaN-aware min/max, 259268b → b034ab0, 0.94×",
    "each node record holds both children's boxes quantised to 8 bits (9 words loaded per traversal step instead of 16), b034ab0 → a3625fc, 0.94×",
    "the first light is read once per SIMD group before any branch instead of per lane inside the light loop, 6bfe8af → 5de8055, 0.96×",
    "the records fetched as texels of a sampled image (with naga's coordinate clamping off: it adds an image-size call per fetch), da6e098 → ac8511d, 0.97×",
    "of a storage image instead, ac2360d → ab7fa43, 0.88×",
    "the triangles as storage-image texels too, ab7fa43 → f9bee1e, 0.91× (all three together, da6e098 → 30ab95a: 0.78×)",
    "the stack's newest four entries in a register, 0f9746b → 32f5909, 0.96× (`ab --cpu-time`, 21 pairs)",
    "records of two texels instead of three (each axis's frame origin stored as its step count and exponent in one word), 32f5909 → c8ac603, 0.98×",
];

/// Kernel changes tried and not kept, each with its measured ratio where
/// the report gives one.
const TRIED: &[&str] = &[
    "the triangles as sampled-image texels (1.00×)",
    "the primitive references and the vertex normals as storage-image texels (0.99×, 1.00×)",
    "the records as sampled texels with naga's clamping (1.00×)",
    "leaves of up to 8 or up to 2 primitives instead of 4 (1.05×, 1.01×)",
    "a smaller traversal stack",
    "eight stack entries in registers instead of four (0.99×)",
    "nodes loaded as two `vec4`s",
    "the watertight test's axis permutation as dot products",
    "4×2-pixel lane tiles",
    "while-while for shadow rays",
    "a branch-free watertight test (within noise)",
    "no distances on the stack (1.09×)",
    "index and distance in one `vec2` stack (1.02×)",
    "the leaf's range kept instead of reloaded (1.00×)",
    "the shader table's first entry or the camera and light count read before any branch (1.00×, 1.01×)",
    "loading at a uniform address inside the traversal loop (as costly as a per-lane one)",
];

/// The list of [`TRIED`] as a sentence: commas, and "and" before the last.
fn tried() -> String {
    match TRIED.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{}, and {last}", rest.join(", ")),
        Some((last, _)) => last.to_string(),
        None => String::new(),
    }
}
