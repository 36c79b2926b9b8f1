// A toon shader: diffuse light quantised into `bands` steps.
struct Params {
    base: vec3<f32>,
    bands: u32,
    gain: f32,
}

fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    let d = max(dot(s.normal, l.to_light), 0.0);
    let n = f32(max(p.bands, 1u));
    let q = floor(d * n) / n;
    return p.base * l.diffuse * (q * l.intensity * p.gain);
}

fn ambient(s: Surface, light_ambient: vec3<f32>, p: Params) -> vec3<f32> {
    return p.base * light_ambient;
}
