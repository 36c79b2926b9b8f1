//! End-to-end checkerboard tests. A checkered plane y = const is seen
//! straight from above by an orthographic camera, so the world point of each
//! pixel centre is known exactly in the test; its cell parity
//! floor(x/s) + floor(y/s) + floor(z/s) is computed here in f64.
//!
//! The sub-shaders are ambient-only (k_a times an ambient-only light of
//! I_a = 1), so each cell colour is exact and the comparison can be tight.

use crate::support;

use glam::DVec3;
use penumbra::render::Image;

const RED: [f32; 3] = [1.0, 0.0, 0.0];
const GREEN: [f32; 3] = [0.0, 1.0, 0.0];
const BLUE: [f32; 3] = [0.0, 0.0, 1.0];

const W: u32 = 128;
const H: u32 = 96;
const HALF_HEIGHT: f64 = 3.0;

/// An orthographic camera at `centre` + 10·Y looking straight down, with the
/// image's up along world −Z: image x runs along +X, image rows along +Z.
fn camera_json(centre: DVec3) -> String {
    let eye = centre + DVec3::new(0.0, 10.0, 0.0);
    format!(
        r#"{{ "position": [{}, {}, {}], "look_at": [{}, {}, {}], "up": [0, 0, -1],
             "projection": "orthographic", "half_height": {HALF_HEIGHT}, "width": {W}, "height": {H} }}"#,
        eye.x, eye.y, eye.z, centre.x, centre.y, centre.z
    )
}

/// World point seen by the centre of pixel (x, y) on the plane at height
/// `plane_y` (spec: ray through the pixel centre, row 0 at the top).
fn world(centre: DVec3, plane_y: f64, x: u32, y: u32) -> DVec3 {
    let hw = HALF_HEIGHT * W as f64 / H as f64;
    let sx = ((x as f64 + 0.5) / W as f64 * 2.0 - 1.0) * hw;
    let sy = (1.0 - (y as f64 + 0.5) / H as f64 * 2.0) * HALF_HEIGHT;
    // right = +X, up = −Z.
    DVec3::new(centre.x + sx, plane_y, centre.z - sy)
}

fn even(p: DVec3, size: f64) -> bool {
    let c = (p / size).floor();
    (c.x + c.y + c.z).rem_euclid(2.0) == 0.0
}

/// Whether p lies at least `margin` (in cells) from every cell border in x
/// and z (y is fixed by the plane and chosen well inside a cell).
fn inside(p: DVec3, size: f64, margin: f64) -> bool {
    [p.x, p.z].iter().all(|c| {
        let f = (c / size).rem_euclid(1.0);
        f > margin && f < 1.0 - margin
    })
}

fn scene_json(centre: DVec3, plane_y: f64, shaders: &str, root: &str) -> String {
    format!(
        r#"{{
  "camera": {},
  "background": [0.5, 0.5, 0.5],
  "shaders": {{
    "red": {{ "type": "phong", "ambient": [1, 0, 0], "diffuse": [0, 0, 0] }},
    "green": {{ "type": "phong", "ambient": [0, 1, 0], "diffuse": [0, 0, 0] }},
    "blue": {{ "type": "phong", "ambient": [0, 0, 1], "diffuse": [0, 0, 0] }},
    {shaders}
  }},
  "objects": [ {{ "type": "plane", "point": [{}, {plane_y}, {}], "normal": [0, 1, 0], "shader": "{root}" }} ],
  "lights": [ {{ "type": "directional", "direction": [0.3, -1, 0.2],
                 "ambient": [1, 1, 1], "diffuse": [0, 0, 0], "specular": [0, 0, 0] }} ]
}}"#,
        camera_json(centre),
        centre.x,
        centre.z
    )
}

fn check(img: &Image, what: &str, mut want: impl FnMut(u32, u32) -> Option<[f32; 3]>) -> u32 {
    let mut n = 0;
    for y in 0..H {
        for x in 0..W {
            if let Some(c) = want(x, y) {
                let got = img.at(x, y);
                assert_eq!(&got[..3], &c[..], "{what}: pixel ({x}, {y})");
                assert_eq!(got[3], 1.0);
                n += 1;
            }
        }
    }
    n
}

const SIMPLE: &str = r#""board": { "type": "checker", "size": 0.5, "even": "red", "odd": "blue" }"#;

#[test]
fn cells_follow_the_parity_of_the_world_point() {
    // Camera off-centre so that the pattern is not symmetric about the image.
    let centre = DVec3::new(0.13, 0.0, -0.29);
    let plane_y = 0.3; // inside the cell 0 <= y < 0.5
    let img = support::render(&support::load_json(&scene_json(
        centre, plane_y, SIMPLE, "board",
    )))
    .image;
    let (mut reds, mut blues) = (0, 0);
    let n = check(&img, "checker", |x, y| {
        let p = world(centre, plane_y, x, y);
        if !inside(p, 0.5, 0.02) {
            return None;
        }
        if even(p, 0.5) {
            reds += 1;
            Some(RED)
        } else {
            blues += 1;
            Some(BLUE)
        }
    });
    assert!(n > W * H * 3 / 4, "{n}");
    assert!(reds > 1000 && blues > 1000);
}

#[test]
fn plane_in_an_odd_layer_swaps_the_colours() {
    // floor(y/s) = 1 for y = 0.7: every cell flips compared with y = 0.3.
    let centre = DVec3::new(0.13, 0.0, -0.29);
    let img = support::render(&support::load_json(&scene_json(
        centre, 0.7, SIMPLE, "board",
    )))
    .image;
    let n = check(&img, "odd layer", |x, y| {
        let p = world(centre, 0.7, x, y);
        let below = world(centre, 0.3, x, y);
        inside(p, 0.5, 0.02).then(|| {
            assert_ne!(even(p, 0.5), even(below, 0.5));
            if even(p, 0.5) {
                RED
            } else {
                BLUE
            }
        })
    });
    assert!(n > W * H * 3 / 4);
}

#[test]
fn plane_on_a_cell_boundary_takes_the_cell_behind_it() {
    // The classic plane y = 0 lies exactly on a cell boundary. The GPU looks
    // the cell up 1/1000 of a cell into the surface, away from the viewer:
    // seen from above, that is the layer below, floor(y/s) = −1.
    let centre = DVec3::new(0.13, 0.0, -0.29);
    let img = support::render(&support::load_json(&scene_json(
        centre, 0.0, SIMPLE, "board",
    )))
    .image;
    let n = check(&img, "boundary plane", |x, y| {
        let p = world(centre, 0.0, x, y) - DVec3::new(0.0, 1e-3 * 0.5, 0.0);
        inside(p, 0.5, 0.02).then(|| if even(p, 0.5) { RED } else { BLUE })
    });
    assert!(n > W * H * 3 / 4);
}

const NESTED: &str = r#""fine": { "type": "checker", "size": 0.125, "even": "red", "odd": "green" },
    "board": { "type": "checker", "size": 0.5, "even": "fine", "odd": "blue" }"#;

fn nested_colour(p: DVec3) -> Option<[f32; 3]> {
    if !inside(p, 0.5, 0.02) || !inside(p, 0.125, 0.05) {
        return None;
    }
    Some(match (even(p, 0.5), even(p, 0.125)) {
        (false, _) => BLUE,
        (true, true) => RED,
        (true, false) => GREEN,
    })
}

#[test]
fn nested_checker_cell_by_cell() {
    let centre = DVec3::new(-0.41, 0.0, 0.17);
    // y = 0.4: floor(0.4/0.5) = 0 and floor(0.4/0.125) = 3 (an odd layer of
    // the fine board, so its y term matters), both well inside their cells.
    let plane_y = 0.4;
    let img = support::render(&support::load_json(&scene_json(
        centre, plane_y, NESTED, "board",
    )))
    .image;
    let mut counts = [0; 3];
    let n = check(&img, "nested", |x, y| {
        let c = nested_colour(world(centre, plane_y, x, y))?;
        counts[[RED, GREEN, BLUE].iter().position(|k| *k == c).unwrap()] += 1;
        Some(c)
    });
    assert!(n > W * H / 3, "{n}");
    assert!(counts.iter().all(|&k| k > 500), "{counts:?}");
}

#[test]
fn far_from_the_origin_the_pattern_is_the_same() {
    // Camera and plane moved by 1e6 in x and z: a whole, even number of cells
    // of both sizes, so the pattern must be pixel for pixel the one near the
    // origin — and the one the test computes from the far world points.
    let near = DVec3::new(-0.41, 0.0, 0.17);
    let offset = DVec3::new(1e6, 0.0, 1e6);
    let far = near + offset;
    let plane_y = 0.4;
    let near_img = support::render(&support::load_json(&scene_json(
        near, plane_y, NESTED, "board",
    )))
    .image;
    let far_img = support::render(&support::load_json(&scene_json(
        far, plane_y, NESTED, "board",
    )))
    .image;
    let n = check(&far_img, "far nested", |x, y| {
        let p = world(far, plane_y, x, y);
        let c = nested_colour(p)?;
        assert_eq!(Some(c), nested_colour(world(near, plane_y, x, y)));
        Some(c)
    });
    assert!(n > W * H / 3, "{n}");
    let differing = (0..H)
        .flat_map(|y| (0..W).map(move |x| (x, y)))
        .filter(|&(x, y)| near_img.at(x, y) != far_img.at(x, y))
        .count();
    assert_eq!(
        differing, 0,
        "pixels differing between the near and the far render"
    );

    // An odd offset in cells flips the parity: 1e6 + 0.5 in x is one more
    // cell of the coarse board (the fine one shifts by 4, even).
    let odd = near + offset + DVec3::new(0.5, 0.0, 0.0);
    let odd_img = support::render(&support::load_json(&scene_json(
        odd, plane_y, NESTED, "board",
    )))
    .image;
    let n = check(&odd_img, "far nested, odd offset", |x, y| {
        let c = nested_colour(world(odd, plane_y, x, y))?;
        let near_c = nested_colour(world(near, plane_y, x, y)).unwrap();
        assert_eq!(
            c == BLUE,
            near_c != BLUE,
            "coarse parity must flip at ({x}, {y})"
        );
        Some(c)
    });
    assert!(n > W * H / 3, "{n}");
}
