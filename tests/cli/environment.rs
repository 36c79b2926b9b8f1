//! `--environment` and `--background` (docs/materials.md, "Environment"):
//! the environment lights a scene whose geometry encloses it (it casts no
//! shadow rays), and the background is the colour where camera rays miss.

use std::process::Command;

/// A grey Lambert sphere of radius 1 at the origin seen from z = 4, with
/// `lights`, and `enclosure`: a sphere of radius 50 around everything.
fn scene(lights: &str, enclosure: bool) -> String {
    let wall = if enclosure {
        r#", {"type": "sphere", "center": [0, 0, 0], "radius": 50, "shader": "grey"}"#
    } else {
        ""
    };
    format!(
        r#"{{
  "camera": {{"position": [0, 0, 4], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40, "width": 32, "height": 32}},
  "background": [0, 0, 0],
  "shaders": {{"grey": {{"type": "phong", "ambient": [0, 0, 0], "diffuse": [0.5, 0.5, 0.5], "specular": [0, 0, 0], "shininess": 1}}}},
  "objects": [{{"type": "sphere", "center": [0, 0, 0], "radius": 1, "shader": "grey"}}{wall}],
  "lights": [{lights}]
}}"#
    )
}

/// Renders `json` to a linear EXR with `extra` arguments: its RGBA pixels.
fn render(json: &str, extra: &[&str]) -> Vec<[f32; 4]> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.json");
    std::fs::write(&path, json).unwrap();
    let out = dir.path().join("out.exr");
    let output = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("render")
        .arg(&path)
        .arg("-o")
        .arg(&out)
        .args(extra)
        .output()
        .expect("run penumbra");
    assert!(
        output.status.success(),
        "{extra:?}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    let img = image::open(&out).unwrap().to_rgba32f();
    img.pixels().map(|p| p.0).collect()
}

/// Pixel (16, 16) sees the sphere head-on, pixel (0, 0) misses it.
const CENTRE: usize = 16 * 32 + 16;

#[test]
fn the_environment_is_not_blocked_by_geometry_enclosing_the_scene() {
    // A directional light from the camera's side (like the default lights
    // of a file without lights): the enclosure blocks it, the sphere is black.
    let point = r#"{"type": "directional", "direction": [0, 0, -1], "intensity": 2}"#;
    let blocked = render(&scene(point, true), &[]);
    assert_eq!(blocked[CENTRE], [0.0, 0.0, 0.0, 1.0]);
    // With the environment and no lights of its own, the enclosed sphere is
    // lit exactly as without the enclosure (no shadow rays), and not black.
    let env = ["--environment", "2"];
    let enclosed = render(&scene("", true), &env);
    let open = render(&scene("", false), &env);
    assert!(enclosed[CENTRE][0] > 0.1, "{:?}", enclosed[CENTRE]);
    assert_eq!(enclosed[CENTRE], open[CENTRE]);
    // The environment's light adds to the file's own.
    let both = render(&scene(point, false), &env);
    let own = render(&scene(point, false), &[]);
    assert!(both[CENTRE][0] > own[CENTRE][0] && both[CENTRE][0] > open[CENTRE][0]);
}

#[test]
fn background_sets_the_colour_where_rays_miss() {
    let point = r#"{"type": "point", "position": [0, 0, 10], "intensity": 50}"#;
    let plain = render(&scene(point, false), &[]);
    assert_eq!(plain[0], [0.0, 0.0, 0.0, 1.0]);
    let set = render(&scene(point, false), &["--background", "0.25,0.5,0.75"]);
    assert_eq!(set[0], [0.25, 0.5, 0.75, 1.0]);
    // Hits keep their colour.
    assert_eq!(set[CENTRE], plain[CENTRE]);
}
