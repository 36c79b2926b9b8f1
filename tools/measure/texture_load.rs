//! How long a large textured glTF file takes to load (decode its PNGs) and
//! to lay out its textures for the device (the mip chains, packed as the
//! shaders read them: `GpuTextures::new`, the host side of the upload), on
//! one thread and on all of rayon's, rounds interleaved; medians, minimum
//! and maximum, and the machine (issue 39, docs/textures.md).
//!
//! ```sh
//! cargo run --release -p penumbra-tools --bin texture_load -- [TEXTURES] [SIDE] [ROUNDS]
//! cargo run --release -p penumbra-tools --bin texture_load -- --model FILE [ROUNDS]
//! ```
//!
//! With `--model`, a glTF file of your own (FlightHelmet) is loaded and
//! uploaded to the default device ROUNDS times (default 3) with all of
//! rayon's threads: per round the load, the texture layout alone and the
//! whole upload as the CLI reports it (`Renderer::upload`, which lays the
//! textures out again and copies them to the device; its BVH build is
//! reported apart), each in wall time and in the process's CPU time (all
//! threads, lavapipe's included), which other processes on a shared machine
//! inflate less. To compare two builds, run each build's binary in turn.
//!
//! The file is generated: TEXTURES quads (default 6), each with a
//! SIDE × SIDE (default 2048) PNG of its own, smooth gradients with noise
//! (compressible as photographs are, not as flat colour is).

use std::path::Path;
use std::time::Instant;

use common::machine::CpuInfo;
use common::ms;
use common::stats::median_min_max;
use penumbra::loaders::{self, LoadOptions};
use penumbra::render::layout::textures::GpuTextures;

fn main() -> anyhow::Result<()> {
    if std::env::args().nth(1).as_deref() == Some("--model") {
        let mut args = std::env::args().skip(2);
        let file = args
            .next()
            .ok_or_else(|| anyhow::anyhow!("--model: give a glTF file"))?;
        let rounds: usize = args.next().map_or(Ok(3), |a| a.parse())?;
        return model(Path::new(&file), rounds);
    }
    let mut args = std::env::args().skip(1);
    let count: usize = args.next().map_or(Ok(6), |a| a.parse())?;
    let side: u32 = args.next().map_or(Ok(2048), |a| a.parse())?;
    let rounds: usize = args.next().map_or(Ok(5), |a| a.parse())?;
    let dir = tempfile::tempdir()?;
    let path = write_model(dir.path(), count, side)?;
    let all = rayon::current_num_threads();
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    // (threads, load ms, layout ms) per run.
    let mut runs: Vec<(usize, f64, f64)> = Vec::new();
    let measure = || -> anyhow::Result<(f64, f64)> {
        let t0 = Instant::now();
        let loaded = loaders::load_scene(&path, &LoadOptions::default())?;
        let t1 = Instant::now();
        let g = GpuTextures::new(&loaded.scene);
        let t2 = Instant::now();
        std::hint::black_box(g.texture_bytes);
        Ok((ms(t1 - t0), ms(t2 - t1)))
    };
    for round in 0..rounds {
        // Alternate which goes first, so that neither always runs warm.
        let order = if round % 2 == 0 { [1, all] } else { [all, 1] };
        for threads in order {
            let (load, layout) = match threads {
                1 => one.install(measure)?,
                _ => measure()?,
            };
            runs.push((threads, load, layout));
        }
    }
    println!("# texture_load: {count} textures of {side}×{side}, {rounds} rounds, interleaved");
    println!("CPU: {}", CpuInfo::read().describe());
    println!(
        "cores: {}; rayon threads: {all}",
        std::thread::available_parallelism()?
    );
    println!("driver: none (host work only; Mesa {})", mesa_version());
    for threads in [1, all] {
        let pick = |f: fn(&(usize, f64, f64)) -> f64| -> Vec<f64> {
            runs.iter().filter(|r| r.0 == threads).map(f).collect()
        };
        let (lm, l0, l1) = median_min_max(&pick(|r| r.1));
        let (gm, g0, g1) = median_min_max(&pick(|r| r.2));
        println!(
            "{threads} thread(s): load (decode) {lm:.0} ms [{l0:.0}, {l1:.0}], \
             texture layout (mip chains) {gm:.0} ms [{g0:.0}, {g1:.0}]"
        );
    }
    // Ratios per round, one thread over all (each round's pair interleaved).
    let ratios = |k: usize| -> Vec<f64> {
        runs.chunks(2)
            .map(|p| {
                let get = |t: usize| {
                    p.iter()
                        .find(|r| r.0 == t)
                        .map_or(f64::NAN, |r| if k == 0 { r.1 } else { r.2 })
                };
                get(1) / get(all)
            })
            .collect()
    };
    let (lm, l0, l1) = median_min_max(&ratios(0));
    let (gm, g0, g1) = median_min_max(&ratios(1));
    println!("speed-up, 1 thread / {all}: load {lm:.2}x [{l0:.2}, {l1:.2}], layout {gm:.2}x [{g0:.2}, {g1:.2}]");
    Ok(())
}

/// This process's CPU time (user and system, all threads) in ms.
fn cpu_ms() -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid timespec to write.
    unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut t) };
    t.tv_sec as f64 * 1e3 + t.tv_nsec as f64 / 1e6
}

/// `--model FILE ROUNDS`: the load, the texture layout and the upload of a
/// glTF file, wall and CPU time per round.
fn model(file: &Path, rounds: usize) -> anyhow::Result<()> {
    let mut renderer = penumbra::render::Renderer::new(&Default::default())?;
    println!("# texture_load --model {}: {rounds} rounds", file.display());
    println!("CPU: {}", CpuInfo::read().describe());
    println!(
        "cores: {}; rayon threads: {}; load average: {}",
        std::thread::available_parallelism()?,
        rayon::current_num_threads(),
        std::fs::read_to_string("/proc/loadavg")?
            .split(' ')
            .take(3)
            .collect::<Vec<_>>()
            .join(" ")
    );
    println!(
        "driver: {} (Mesa {})",
        renderer.device().name,
        mesa_version()
    );
    println!("round | load wall/cpu ms | texture layout wall/cpu ms | upload wall/cpu ms (BVH wall ms) | textures MiB");
    let mut rows: Vec<[f64; 6]> = Vec::new();
    for round in 0..rounds {
        let (w0, c0) = (Instant::now(), cpu_ms());
        let loaded = loaders::load_scene(file, &LoadOptions::default())?;
        let (w1, c1) = (Instant::now(), cpu_ms());
        let g = GpuTextures::new(&loaded.scene);
        let (w2, c2) = (Instant::now(), cpu_ms());
        let bytes = g.texture_bytes;
        drop(g);
        let (w3, c3) = (Instant::now(), cpu_ms());
        let uploaded = renderer.upload(&loaded.scene)?;
        let (w4, c4) = (Instant::now(), cpu_ms());
        let (bvh, _) = uploaded.upload_timings();
        drop(uploaded);
        let row = [
            ms(w1 - w0),
            c1 - c0,
            ms(w2 - w1),
            c2 - c1,
            ms(w4 - w3),
            c4 - c3,
        ];
        println!(
            "{round} | {:.0} / {:.0} | {:.0} / {:.0} | {:.0} / {:.0} ({:.0}) | {:.1}",
            row[0],
            row[1],
            row[2],
            row[3],
            row[4],
            row[5],
            ms(bvh),
            bytes as f64 / 1048576.0
        );
        rows.push(row);
    }
    let names = [
        "load wall",
        "load cpu",
        "layout wall",
        "layout cpu",
        "upload wall",
        "upload cpu",
    ];
    for (i, name) in names.iter().enumerate() {
        let v: Vec<f64> = rows.iter().map(|r| r[i]).collect();
        let (m, lo, hi) = median_min_max(&v);
        println!("{name}: {m:.0} ms [{lo:.0}, {hi:.0}]");
    }
    Ok(())
}

/// The installed Mesa's version, from dpkg (`unknown` without it).
fn mesa_version() -> String {
    std::process::Command::new("dpkg-query")
        .args(["-W", "-f=${Version}", "mesa-vulkan-drivers"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map_or("unknown".into(), |o| {
            String::from_utf8_lossy(&o.stdout).into_owned()
        })
}

/// Writes `model.gltf` with `count` textured quads into `dir`.
fn write_model(dir: &Path, count: usize, side: u32) -> anyhow::Result<std::path::PathBuf> {
    let mut seed = 0x2545_f491_u32;
    let mut nodes = Vec::new();
    let mut meshes = Vec::new();
    let mut materials = Vec::new();
    let mut textures = Vec::new();
    let mut images = Vec::new();
    for i in 0..count {
        let img = image::RgbaImage::from_fn(side, side, |x, y| {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            let n = (seed & 15) as u8;
            let g = |v: u32, k: u32| ((v * 255 / side + k * 40) % 240) as u8;
            image::Rgba([g(x, i as u32) + n, g(y, 1) + n, g(x + y, 2) / 2 + n, 255])
        });
        let name = format!("t{i}.png");
        img.save(dir.join(&name))?;
        images.push(serde_json::json!({ "uri": name }));
        textures.push(serde_json::json!({ "source": i }));
        materials.push(serde_json::json!({ "pbrMetallicRoughness": {
            "baseColorTexture": { "index": i }, "metallicFactor": 0 } }));
        meshes.push(serde_json::json!({ "primitives": [{
            "attributes": { "POSITION": 0, "TEXCOORD_0": 1 }, "indices": 2, "material": i }] }));
        nodes.push(serde_json::json!({ "mesh": i, "translation": [i as f32 * 1.1, 0, 0] }));
    }
    let positions: [f32; 12] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0];
    let uvs: [f32; 8] = [0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0];
    let indices: [u16; 6] = [0, 1, 2, 0, 2, 3];
    let mut bin: Vec<u8> = positions.iter().flat_map(|x| x.to_le_bytes()).collect();
    bin.extend(uvs.iter().flat_map(|x| x.to_le_bytes()));
    bin.extend(indices.iter().flat_map(|x| x.to_le_bytes()));
    std::fs::write(dir.join("model.bin"), &bin)?;
    let json = serde_json::json!({
        "asset": { "version": "2.0" },
        "scene": 0,
        "scenes": [{ "nodes": (0..count).collect::<Vec<_>>() }],
        "nodes": nodes, "meshes": meshes, "materials": materials,
        "textures": textures, "images": images,
        "buffers": [{ "uri": "model.bin", "byteLength": bin.len() }],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": 48 },
            { "buffer": 0, "byteOffset": 48, "byteLength": 32 },
            { "buffer": 0, "byteOffset": 80, "byteLength": 12 }
        ],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
              "min": [0, 0, 0], "max": [1, 1, 0] },
            { "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2" },
            { "bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR" }
        ]
    });
    let path = dir.join("model.gltf");
    std::fs::write(&path, serde_json::to_vec(&json)?)?;
    Ok(path)
}
