//! The environment light (docs/materials.md, "Environment"), measured on
//! glTF's metallic-roughness chart (`scenes/metal_spheres.gltf`, its
//! roughnesses squared so that the metals run from 0.04 to 1) over its
//! floor, lit by the environment alone (64 directions per pass):
//!
//! 1. **Error of the estimator** at 1, 4 and 16 spp, before (directions
//!    uniform on the sphere) and after (the mixture), against a converged
//!    `f64` reference image (GT_SPP spp of the mixture), both in the `f64`
//!    reference (same seeds for both estimators) and, for the mixture, on
//!    the GPU: RMSE over the pixels, relative to the reference's mean.
//! 2. **Traced or unshadowed**: the reference with the environment's samples
//!    traced by shadow rays against the unshadowed one (the GPU's), both at
//!    SHADOW_SPP spp: mean and 99th percentile of the per-pixel difference.
//! 3. **Cost**: GPU frame render time at 1 and 16 spp of the environment
//!    (64 unshadowed directions), of a rectangle light of 64 shadowed
//!    samples, and of one directional light, rendered in turn ROUNDS times
//!    (interleaved); medians and ranges, and ratios within a round.
//!
//! Writes the tables to `docs/environment_bench.md`.
//!
//! ```sh
//! cargo run -p penumbra-tools --bin environment_bench [-- ROUNDS [OUTPUT.md]]
//! ```

use std::fmt::Write as _;
use std::path::PathBuf;

use common::ms;
use common::stats::{median_min_max, percentile};
use glam::{DVec3, Vec3};
use penumbra::frame::Image;
use penumbra::loaders::{self, LoadOptions};
use penumbra::reference::environment::Options;
use penumbra::render::{RenderRequest, Renderer, RendererOptions, Sampler, Sampling};
use penumbra::scene::{Light, LightKind, Scene, Shader, ENVIRONMENT_MIXTURE};

const WIDTH: u32 = 192;
const HEIGHT: u32 = 108;
const SAMPLES: u32 = 64;
const GT_SPP: u32 = 256;
const SHADOW_SPP: u32 = 64;

/// The chart at WIDTH×HEIGHT with `light` only, metal and dielectric
/// roughnesses squared (0.04, 0.16, 0.36, 0.64, 1).
fn chart(light: LightKind) -> anyhow::Result<Scene> {
    let path = common::repo_root().join("scenes/metal_spheres.gltf");
    let opts = LoadOptions {
        width: Some(WIDTH),
        height: Some(HEIGHT),
        ..Default::default()
    };
    let mut scene = loaders::load_scene(&path, &opts)?.scene;
    for s in &mut scene.shaders {
        if let Shader::MetallicRoughness(m) = s {
            m.roughness *= m.roughness;
        }
    }
    scene.lights = vec![Light {
        kind: light,
        intensity: 1.0,
        ambient: Vec3::ZERO,
        diffuse: Vec3::ONE,
        specular: Vec3::ONE,
    }];
    scene.background = Vec3::ZERO;
    Ok(scene)
}

fn sampling(spp: u32, seed: u32) -> Sampling {
    Sampling {
        spp,
        seed,
        time_budget: None,
    }
}

/// Per-pixel absolute differences of the RGB mean of two images.
fn differences(a: &Image, b: &Image) -> Vec<f64> {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .map(|(p, q)| {
            (0..3)
                .map(|c| (p[c] as f64 - q[c] as f64).abs())
                .sum::<f64>()
                / 3.0
        })
        .collect()
}

/// RMSE of `a` against `truth` over all channels, relative to the mean of
/// `truth`.
fn relative_rmse(a: &Image, truth: &Image) -> f64 {
    let (mut se, mut sum, mut n) = (0.0, 0.0, 0.0);
    for (p, q) in a.pixels.iter().zip(&truth.pixels) {
        for c in 0..3 {
            let d = p[c] as f64 - q[c] as f64;
            se += d * d;
            sum += q[c] as f64;
            n += 1.0;
        }
    }
    (se / n).sqrt() / (sum / n)
}

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let rounds: usize = match args.next() {
        Some(n) => n.parse()?,
        None => 7,
    };
    let out = args
        .next()
        .map(PathBuf::from)
        .unwrap_or_else(|| common::repo_root().join("docs/environment_bench.md"));
    let env = chart(LightKind::Environment {
        up: DVec3::Y,
        samples: SAMPLES,
    })?;
    let sampler = Sampler::default();
    let uniform = Options {
        mixture: penumbra::scene::EnvironmentMixture {
            uniform: 1.0,
            cosine: 0.0,
            ..ENVIRONMENT_MIXTURE
        },
        shadowed: false,
    };
    let mixture = Options::default();
    eprintln!("reference at {GT_SPP} spp…");
    let truth = penumbra::reference::render_with_environment(
        &env,
        &sampling(GT_SPP, 1000),
        sampler,
        &mixture,
    )
    .image;

    let mut r = Renderer::new(&RendererOptions::default())?;
    let up_env = r.upload(&env)?;
    let mut error_rows = String::new();
    for spp in [1, 4, 16] {
        let mut cells = Vec::new();
        for options in [&uniform, &mixture] {
            let f = penumbra::reference::render_with_environment(
                &env,
                &sampling(spp, 1),
                sampler,
                options,
            );
            cells.push(relative_rmse(&f.image, &truth));
        }
        let mut req = RenderRequest::new(WIDTH, HEIGHT);
        req.sampling = sampling(spp, 1);
        let g = r.render(&up_env, req)?;
        cells.push(relative_rmse(&g.frame.image, &truth));
        let _ = writeln!(
            error_rows,
            "| {spp} | {:.4} | {:.4} | {:.4} | {:.2} |",
            cells[0],
            cells[1],
            cells[2],
            cells[0] / cells[1]
        );
    }

    eprintln!("shadowed against unshadowed at {SHADOW_SPP} spp…");
    let traced = Options {
        shadowed: true,
        ..Options::default()
    };
    let unshadowed = penumbra::reference::render_with_environment(
        &env,
        &sampling(SHADOW_SPP, 2),
        sampler,
        &mixture,
    );
    let shadowed = penumbra::reference::render_with_environment(
        &env,
        &sampling(SHADOW_SPP, 2),
        sampler,
        &traced,
    );
    let d = differences(&unshadowed.image, &shadowed.image);
    let mean_d = d.iter().sum::<f64>() / d.len() as f64;
    let p99 = percentile(&d, 99.0);
    let mean_value = unshadowed
        .image
        .pixels
        .iter()
        .map(|p| (p[0] + p[1] + p[2]) as f64 / 3.0)
        .sum::<f64>()
        / d.len() as f64;

    eprintln!("frame cost…");
    // A rectangle light of the same number of samples above the chart,
    // shadowed, and one directional light.
    let rect = chart(LightKind::Rect {
        // edge1 × edge2 = −y: it shines down on the chart.
        corner: DVec3::new(-3.0, 4.0, -1.5),
        edge1: DVec3::new(6.0, 0.0, 0.0),
        edge2: DVec3::new(0.0, 0.0, 3.0),
        samples: SAMPLES,
    })?;
    let directional = chart(LightKind::Directional {
        direction: DVec3::new(0.3, -1.0, -0.4).normalize(),
    })?;
    let variants = [
        ("one directional light", r.upload(&directional)?),
        ("environment, 64 directions, unshadowed", up_env),
        ("rectangle light, 64 samples, shadowed", r.upload(&rect)?),
    ];
    let mut cost_rows = String::new();
    for spp in [1, 16] {
        let mut times: Vec<Vec<f64>> = vec![Vec::new(); variants.len()];
        for (_, up) in &variants {
            // Compile and warm up.
            let mut req = RenderRequest::new(WIDTH, HEIGHT);
            req.sampling = sampling(spp, 0);
            r.render(up, req)?;
        }
        for _ in 0..rounds {
            for (i, (_, up)) in variants.iter().enumerate() {
                let mut req = RenderRequest::new(WIDTH, HEIGHT);
                req.sampling = sampling(spp, 0);
                let f = r.render(up, req)?;
                times[i].push(ms(f.frame.stats.timings.render));
            }
        }
        for (i, (name, _)) in variants.iter().enumerate() {
            let (med, lo, hi) = median_min_max(&times[i]);
            let ratios: Vec<f64> = times[i].iter().zip(&times[0]).map(|(a, b)| a / b).collect();
            let (rm, rlo, rhi) = median_min_max(&ratios);
            let _ = writeln!(
                cost_rows,
                "| {spp} | {name} | {med:.1} [{lo:.1}–{hi:.1}] | {rm:.2} [{rlo:.2}–{rhi:.2}] |"
            );
        }
    }

    let device = r.device();
    let mut o = String::new();
    let _ = writeln!(
        o,
        "# The environment light: estimator error, shadows, cost\n\n\
         Generated by `cargo run -p penumbra-tools --bin environment_bench` \
         (`tools/measure/environment_bench.rs`): `scenes/metal_spheres.gltf` at {WIDTH}×{HEIGHT}, \
         its roughnesses squared (metals and dielectrics at 0.04, 0.16, 0.36, 0.64, 1), over its \
         floor, lit by the environment alone ({SAMPLES} directions per pass), background black.\n\n\
         {}",
        common::machine::report_table(device),
    );
    let _ = writeln!(
        o,
        "## Error against the converged reference\n\n\
         RMSE over all pixels and channels relative to the mean of the `f64` reference at {GT_SPP} spp \
         (the mixture, seed 1000); the estimates use seed 1. \"Uniform\" is the estimator before \
         (directions uniform on the sphere), \"mixture\" the one now.\n\n\
         | spp | reference, uniform | reference, mixture | GPU, mixture | uniform / mixture |\n|---|---|---|---|---|\n{error_rows}"
    );
    let _ = writeln!(
        o,
        "## Traced with shadow rays or unshadowed\n\n\
         The `f64` reference at {SHADOW_SPP} spp (seed 2, the mixture), the environment's samples \
         traced to infinity against not traced: per pixel the mean over RGB of |unshadowed − shadowed|. \
         Mean pixel value (unshadowed) {mean_value:.4}; mean difference {mean_d:.4} ({:.1} % of it); \
         99th percentile {p99:.4}.\n",
        100.0 * mean_d / mean_value
    );
    let _ = writeln!(
        o,
        "## Frame cost on the GPU\n\n\
         Render phase per frame, {rounds} rounds of the three variants in turn after a compile and \
         warm-up frame each; ratios to the directional light within a round.\n\n\
         | spp | Light | Render ms/frame, median [min–max] | / directional, median [min–max] |\n|---|---|---|---|\n{cost_rows}"
    );
    print!("{o}");
    std::fs::write(&out, &o)?;
    eprintln!("wrote {}", out.display());
    Ok(())
}
