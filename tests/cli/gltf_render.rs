//! `penumbra render` of glTF files (issue 39): the summary line states the
//! triangle count, EXT_mesh_gpu_instancing's instances expanded, and the
//! texture memory.

use std::path::Path;
use std::process::Command;

use serde_json::{json, Value};

/// Renders `scene` at 48×36 into `dir` and returns its summary line.
fn summary_of(scene: &Path, dir: &Path) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(["render".as_ref(), scene.as_os_str(), "-o".as_ref()])
        .arg(dir.join("out.png"))
        .args(["--width", "48", "--height", "36"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
        .lines()
        .find(|l| l.contains(" Mrays/s"))
        .expect("summary")
        .to_string()
}

#[test]
fn the_summary_line_counts_instanced_triangles_and_texture_memory() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/khronos/BoxTextured/BoxTextured.gltf");
    let mut gltf: Value = serde_json::from_slice(&std::fs::read(data).unwrap()).unwrap();
    // The box (12 triangles) drawn 3 times, side by side.
    let offsets: Vec<u8> = [[0f32, 0.0, 0.0], [2.0, 0.0, 0.0], [4.0, 0.0, 0.0]]
        .iter()
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        crate::base64::encode(&offsets)
    );
    gltf["buffers"]
        .as_array_mut()
        .unwrap()
        .push(json!({ "byteLength": 36, "uri": uri }));
    gltf["bufferViews"]
        .as_array_mut()
        .unwrap()
        .push(json!({ "buffer": 1, "byteLength": 36 }));
    let view = gltf["bufferViews"].as_array().unwrap().len() - 1;
    gltf["accessors"]
        .as_array_mut()
        .unwrap()
        .push(json!({ "bufferView": view, "componentType": 5126, "count": 3, "type": "VEC3" }));
    let acc = gltf["accessors"].as_array().unwrap().len() - 1;
    gltf["extensionsUsed"] = json!(["EXT_mesh_gpu_instancing"]);
    gltf["nodes"][2]["extensions"] =
        json!({ "EXT_mesh_gpu_instancing": { "attributes": { "TRANSLATION": acc } } });
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("boxes.gltf");
    std::fs::write(&scene, serde_json::to_vec(&gltf).unwrap()).unwrap();
    let line = summary_of(&scene, dir.path());
    assert!(line.contains(" | 36 triangles"), "{line}");
    assert!(
        line.contains(" | textures ") && line.contains(" MiB (mip-maps included)"),
        "{line}"
    );
}

/// The summary line names each pipeline the render built with the driver's
/// compile time, and those times add up to the phase's total (each printed
/// to 0.1 ms).
#[test]
fn the_summary_line_reports_the_driver_compile_of_each_pipeline() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/textured.json");
    let dir = tempfile::tempdir().unwrap();
    let line = summary_of(&scene, dir.path());
    let ms = |s: &str| -> f64 { s.trim().trim_end_matches(" ms").parse().unwrap() };
    let total = ms(line
        .split("driver compile ")
        .nth(1)
        .and_then(|r| r.split(',').next())
        .expect("the phase"));
    let each = line
        .split(" | driver compile: ")
        .nth(1)
        .and_then(|rest| rest.split(" | ").next())
        .expect("per pipeline");
    let parts: Vec<(&str, f64)> = each
        .split(", ")
        .map(|p| {
            // "NAME 12.3 ms"
            let rest = p.strip_suffix(" ms").expect("a time in ms");
            let (name, t) = rest.rsplit_once(' ').expect("a name and a time");
            (name, ms(t))
        })
        .collect();
    let names: Vec<&str> = parts.iter().map(|(n, _)| *n).collect();
    // The hit stage and one shade pipeline per shading file of the scene:
    // painted.wgsl, Blinn-Phong and Phong.
    assert!(names.contains(&"hit"), "{line}");
    for file in ["painted.wgsl", "blinn_phong.wgsl", "phong.wgsl"] {
        assert!(
            names
                .iter()
                .any(|n| n.starts_with("shade ") && n.ends_with(file)),
            "{file}: {line}"
        );
    }
    let sum: f64 = parts.iter().map(|(_, t)| t).sum();
    assert!(
        (sum - total).abs() <= 0.05 * (parts.len() + 1) as f64,
        "{sum} vs {total}: {line}"
    );
}
