//! The hostile-input table (docs/hostile_inputs.md): builds one input per
//! class of issue 36 (user shaders that loop, hoard memory or nest deeply,
//! texture bombs, a merge of 10,000 copies, control characters in names,
//! indices above u32), runs the `penumbra` binary on each as a user would,
//! and prints a Markdown row per case: what penumbra did (exit status and the
//! first line of stderr), its peak memory (`ru_maxrss` from wait4) and its
//! wall time. Every case runs under a hard kill after `--kill-after`
//! seconds, so the table itself cannot hang.
//!
//! `cargo build && cargo run -p penumbra-tools --bin hostile -- --penumbra target/debug/penumbra`

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use clap::Parser;

#[derive(Parser)]
struct Args {
    /// The penumbra binary to run.
    #[arg(long, default_value = "target/debug/penumbra")]
    penumbra: PathBuf,
    /// Kill a case after this many seconds.
    #[arg(long, default_value_t = 150)]
    kill_after: u64,
    /// Run only the cases whose name contains this.
    #[arg(long)]
    only: Option<String>,
}

/// What one run did.
struct Outcome {
    status: String,
    stderr_first: String,
    stderr_lines: usize,
    peak_mib: f64,
    wall: Duration,
}

/// Runs `cmd` to its end (or kills it after `kill_after`), reading stderr,
/// and takes its peak resident memory from wait4.
// The child is reaped by wait4 (which also gives its rusage), not by
// `Child::wait`.
#[allow(clippy::zombie_processes)]
fn run(mut cmd: Command, kill_after: Duration) -> Outcome {
    let t = Instant::now();
    let child = cmd
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start penumbra");
    let pid = child.id() as i32;
    let mut stderr = child.stderr.expect("stderr");
    let reader = std::thread::spawn(move || {
        let mut s = Vec::new();
        let _ = std::io::Read::read_to_end(&mut stderr, &mut s);
        s
    });
    let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let killer = {
        let done = done.clone();
        std::thread::spawn(move || {
            let end = Instant::now() + kill_after;
            while Instant::now() < end {
                if done.load(std::sync::atomic::Ordering::Relaxed) {
                    return false;
                }
                std::thread::sleep(Duration::from_millis(20));
            }
            // SAFETY: kill(2) on our child, not yet reaped.
            unsafe { libc::kill(pid, libc::SIGKILL) };
            true
        })
    };
    let mut status = 0;
    // SAFETY: a zeroed rusage is a valid out-parameter.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: waits for our own child and fills `usage`.
    unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
    let wall = t.elapsed();
    done.store(true, std::sync::atomic::Ordering::Relaxed);
    let killed = killer.join().unwrap_or(false);
    let stderr = String::from_utf8_lossy(&reader.join().unwrap_or_default()).into_owned();
    let status = if killed {
        format!("killed after {} s", kill_after.as_secs())
    } else if libc::WIFEXITED(status) {
        format!("exit {}", libc::WEXITSTATUS(status))
    } else {
        format!("signal {}", libc::WTERMSIG(status))
    };
    let first = stderr
        .lines()
        .find(|l| !l.starts_with("note: "))
        .unwrap_or("")
        .to_string();
    Outcome {
        status,
        stderr_lines: stderr.lines().filter(|l| !l.starts_with("note: ")).count(),
        stderr_first: first,
        peak_mib: usage.ru_maxrss as f64 / 1024.0,
        wall,
    }
}

/// A scene of one sphere shaded by `user.wgsl` (Params `weight`), 64×48.
fn shader_case(dir: &Path, source: &str) -> PathBuf {
    std::fs::write(dir.join("user.wgsl"), source).unwrap();
    let scene = r#"{
      "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40, "width": 64, "height": 48},
      "shaders": {"user": {"type": "wgsl", "file": "user.wgsl", "params": {"weight": 1}}},
      "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "shader": "user"}],
      "lights": [{"type": "point", "position": [2, 2, 3], "intensity": 10}]
    }"#;
    std::fs::write(dir.join("scene.json"), scene).unwrap();
    dir.join("scene.json")
}

/// A scene whose sphere's diffuse texture is `name` (`bytes`).
fn texture_case(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    if !bytes.is_empty() {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    let scene = serde_json::json!({
        "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40, "width": 64, "height": 48},
        "shaders": {"t": {"type": "phong", "ambient": [0.1, 0.1, 0.1], "diffuse": {"texture": name},
                          "specular": [0, 0, 0], "shininess": 1}},
        "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "shader": "t"}],
        "lights": [{"type": "point", "position": [2, 2, 3], "intensity": 10}]
    });
    std::fs::write(dir.join("scene.json"), scene.to_string()).unwrap();
    dir.join("scene.json")
}

/// `shade` of a `Params { weight }` shader with `body` before its return.
fn shade(body: &str) -> String {
    format!(
        "struct Params {{ weight: f32, }}\nfn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {{\n{body}\n    return s.normal;\n}}\n"
    )
}

/// A PNG of side² 1-bit grey texels: a few KB.
fn png_bomb(side: u32) -> Vec<u8> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, side, side);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::One);
    let mut writer = encoder.write_header().unwrap();
    let mut stream = writer.stream_writer().unwrap();
    let row = vec![0u8; side.div_ceil(8) as usize];
    for _ in 0..side {
        std::io::Write::write_all(&mut stream, &row).unwrap();
    }
    stream.finish().unwrap();
    writer.finish().unwrap();
    out
}

/// A 16×16 JPEG whose frame header claims side² texels.
fn jpeg_bomb(side: u16) -> Vec<u8> {
    let img = image::RgbImage::from_pixel(16, 16, image::Rgb([120, 90, 60]));
    let mut jpeg = Vec::new();
    img.write_to(
        &mut std::io::Cursor::new(&mut jpeg),
        image::ImageFormat::Jpeg,
    )
    .unwrap();
    let mut i = 2;
    while jpeg[i + 1] != 0xC0 {
        i += 2 + usize::from(u16::from_be_bytes([jpeg[i + 2], jpeg[i + 3]]));
    }
    jpeg[i + 5..i + 7].copy_from_slice(&side.to_be_bytes());
    jpeg[i + 7..i + 9].copy_from_slice(&side.to_be_bytes());
    jpeg
}

/// One row of the table: the case's name, what it is, and the command.
struct Case {
    name: &'static str,
    input: String,
    args: Vec<String>,
    dir: tempfile::TempDir,
}

fn arg(p: &Path) -> String {
    p.display().to_string()
}

/// The cases, and the folders that must outlive them (the part that the
/// merge case links to).
fn cases(penumbra: &Path) -> (Vec<Case>, Vec<tempfile::TempDir>) {
    let mut cases = Vec::new();
    let mut add = |name: &'static str, input: String, make: &dyn Fn(&Path) -> (Vec<String>,)| {
        let dir = tempfile::tempdir().unwrap();
        let (args,) = make(dir.path());
        cases.push(Case {
            name,
            input,
            args,
            dir,
        });
    };
    let r = |dir: &Path, scene: PathBuf, extra: &[&str]| {
        let mut args = vec![
            "render".to_string(),
            arg(&scene),
            "-o".into(),
            arg(&dir.join("out.png")),
        ];
        args.extend(extra.iter().map(|s| s.to_string()));
        (args,)
    };
    add(
        "loop",
        "`shade` with a loop whose exit never comes (run-time condition)".into(),
        &|d| {
            r(d, shader_case(d, &shade("    var c = 0.0;\n    loop { if (c > abs(p.weight) * 1e30 + 1e30) { break; } c += 1.0; }\n    if (c == 3.0) { return vec3<f32>(c); }")), &["--time-limit", "5"])
        },
    );
    add(
        "loop 2^31",
        "`shade` with a loop of 2^31 iterations".into(),
        &|d| {
            r(d, shader_case(d, &shade("    var c = 0.0;\n    for (var i = 0u; i < 2147483648u; i++) { c += p.weight; }\n    if (c == 3.0) { return vec3<f32>(c); }")), &["--time-limit", "5"])
        },
    );
    add(
        "array 10^8",
        "`var a: array<f32, 100000000>` in `shade`".into(),
        &|d| {
            r(d, shader_case(d, &shade("    var a: array<f32, 100000000>;\n    a[u32(s.normal.x)] = 1.0;\n    if (a[1] == 2.0) { return vec3<f32>(1.0); }")), &[])
        },
    );
    add(
        "array 10^6",
        "`var a: array<f32, 1000000>` in `shade`".into(),
        &|d| {
            r(d, shader_case(d, &shade("    var a: array<f32, 1000000>;\n    a[u32(s.normal.x)] = 1.0;\n    if (a[1] == 2.0) { return vec3<f32>(1.0); }")), &[])
        },
    );
    add(
        "private array",
        "`var<private> a: array<f32, 1000000>`".into(),
        &|d| {
            r(
                d,
                shader_case(
                    d,
                    &format!(
                        "var<private> a: array<f32, 1000000>;\n{}",
                        shade("    a[u32(s.normal.x)] = 1.0;")
                    ),
                ),
                &[],
            )
        },
    );
    add(
        "workgroup array",
        "`var<workgroup> a: array<f32, 1000000>`".into(),
        &|d| {
            r(
                d,
                shader_case(
                    d,
                    &format!("var<workgroup> a: array<f32, 1000000>;\n{}", shade("")),
                ),
                &[],
            )
        },
    );
    add(
        "deep sum",
        "`return` of a sum of 30,000 terms (60 KB)".into(),
        &|d| {
            let sum = vec!["x"; 30000].join("+");
            r(d, shader_case(d, &format!("struct Params {{ weight: f32, }}\nfn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {{\n    let x = p.weight;\n    return vec3<f32>({sum});\n}}\n")), &[])
        },
    );
    add(
        "nested parentheses",
        "2,000 nested parentheses".into(),
        &|d| {
            let e = format!("{}1.0{}", "(".repeat(2000), ")".repeat(2000));
            r(d, shader_case(d, &shade(&format!("    let x = {e};"))), &[])
        },
    );
    add(
        "multibyte comment",
        "`/* é ✓ 日本 */` in a shader (must render)".into(),
        &|d| {
            r(
                d,
                shader_case(d, &format!("/* é ✓ 日本 */\n{}", shade("    // ü"))),
                &[],
            )
        },
    );
    add(
        "50 MB of constants",
        "a 50 MB shader of `const` declarations".into(),
        &|d| {
            let mut s = String::new();
            let mut i = 0;
            while s.len() < 50 << 20 {
                s.push_str(&format!("const c{i}: f32 = {i}.0;\n"));
                i += 1;
            }
            r(d, shader_case(d, &format!("{s}{}", shade(""))), &[])
        },
    );
    add("200,000 functions", "200,000 functions".into(), &|d| {
        let f: String = (0..200000).map(|i| format!("fn f{i}() {{}}\n")).collect();
        r(d, shader_case(d, &format!("{f}{}", shade(""))), &[])
    });
    add(
        "Params 10,000 fields",
        "`Params` with 10,000 fields".into(),
        &|d| {
            let fields: String = (0..10000).map(|i| format!("f{i}: f32, ")).collect();
            r(d, shader_case(d, &format!("struct Params {{ weight: f32, {fields} }}\nfn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {{ return s.normal; }}\n")), &[])
        },
    );
    add(
        "Params 100 fields",
        "`Params` with 100 fields".into(),
        &|d| {
            let fields: String = (0..100).map(|i| format!("f{i}: f32, ")).collect();
            r(d, shader_case(d, &format!("struct Params {{ weight: f32, {fields} }}\nfn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {{ return s.normal; }}\n")), &[])
        },
    );
    add(
        "resources",
        "`@group(0) @binding(9) var<storage> x: array<u32>;`".into(),
        &|d| {
            r(
                d,
                shader_case(
                    d,
                    &format!(
                        "@group(0) @binding(9) var<storage> x: array<u32>;\n{}",
                        shade("")
                    ),
                ),
                &[],
            )
        },
    );
    add(
        "PNG bomb",
        "9.9 KB PNG, 9000×9000 1-bit grey, `--max-scene-memory 1024`".into(),
        &|d| {
            r(
                d,
                texture_case(d, "bomb.png", &png_bomb(9000)),
                &["--max-scene-memory", "1024"],
            )
        },
    );
    add(
        "PNG bomb (defaults)",
        "the same PNG with the default 4 GiB budget (a valid image within every limit)".into(),
        &|d| r(d, texture_case(d, "bomb.png", &png_bomb(9000)), &[]),
    );
    add(
        "JPEG header bomb",
        "a JPEG of 16×16 texels whose header says 16384×16384".into(),
        &|d| r(d, texture_case(d, "bomb.jpg", &jpeg_bomb(16384)), &[]),
    );
    add(
        "control characters",
        "a texture named `x<ESC>[31m<CR><LF>error: forged<NUL>.png`".into(),
        &|d| {
            r(
                d,
                texture_case(d, "x\u{1b}[31m\r\nerror: forged\0.png", &[]),
                &[],
            )
        },
    );
    add(
        "index 2^32",
        "a glTF `baseColorTexture.index` of 4294967296".into(),
        &|d| {
            let gltf = serde_json::json!({
                "asset": {"version": "2.0"},
                "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 4294967296u64}}}],
                "meshes": [], "nodes": [], "scenes": [{"nodes": []}]
            });
            std::fs::write(d.join("model.gltf"), gltf.to_string()).unwrap();
            r(d, d.join("model.gltf"), &[])
        },
    );
    let part = {
        let dir = tempfile::tempdir().unwrap();
        let scene = shader_case(dir.path(), &shade(""));
        let out = dir.path().join("part.exr");
        let ok = Command::new(penumbra)
            .args(["render", &arg(&scene), "--tile", "0/1", "-o", &arg(&out)])
            .stdout(Stdio::null())
            .status()
            .map(|s| s.success())
            .unwrap_or(false);
        ok.then_some((dir, out))
    };
    let mut keep = Vec::new();
    if let Some((dir, part)) = part {
        add(
            "merge 10,000 copies",
            "`penumbra merge` of one part and 10,000 hard links to it".into(),
            &|d| {
                let mut args = vec![
                    "merge".to_string(),
                    "-o".into(),
                    arg(&d.join("out.png")),
                    arg(&part),
                ];
                for i in 0..10000 {
                    let link = d.join(format!("copy{i:05}.exr"));
                    std::fs::hard_link(&part, &link).unwrap();
                    args.push(arg(&link));
                }
                (args,)
            },
        );
        keep.push(dir);
    }
    (cases, keep)
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    let cpu = common::machine::CpuInfo::read();
    println!("CPU: {}", cpu.describe());
    println!();
    println!("| case | input | what penumbra does | stderr lines | output written | peak memory | time |");
    println!("|---|---|---|---|---|---|---|");
    let (cases, _keep) = cases(&args.penumbra);
    for case in cases {
        if args
            .only
            .as_ref()
            .is_some_and(|o| !case.name.contains(o.as_str()))
        {
            continue;
        }
        let mut cmd = Command::new(&args.penumbra);
        cmd.args(&case.args);
        let o = run(cmd, Duration::from_secs(args.kill_after));
        let written = case.dir.path().join("out.png").exists();
        let mut first = o.stderr_first.replace('|', "\\|");
        if first.chars().count() > 160 {
            first = first.chars().take(160).collect::<String>() + "…";
        }
        let first = first.replace(case.dir.path().to_str().unwrap_or("\u{0}"), "DIR");
        println!(
            "| {} | {} | {}: `{}` | {} | {} | {:.0} MiB | {:.2} s |",
            case.name,
            case.input,
            o.status,
            first,
            o.stderr_lines,
            if written { "yes" } else { "no" },
            o.peak_mib,
            o.wall.as_secs_f64()
        );
    }
    Ok(())
}
