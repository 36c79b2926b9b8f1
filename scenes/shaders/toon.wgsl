// Toon shading: the diffuse term quantised into `bands` flat steps, and a
// hard-edged Blinn-Phong highlight. Written against the engine's interface
// (shaders/shading/interface.wgsl; rules in scenes/README.md, `wgsl`).
//
// The bands are taken per light sample, so this shader is meant for point,
// spot and directional lights (an area light's samples would each be
// quantised on their own).

struct Params {
    // Colour of the lit surface (and of its ambient term).
    base: vec3<f32>,
    // Number of diffuse steps between unlit and fully lit (at least 1).
    bands: u32,
    // Colour of the highlight.
    highlight: vec3<f32>,
    // Size of the highlight: the Blinn-Phong exponent it is cut from.
    shininess: f32,
}

fn ambient(s: Surface, light_ambient: vec3<f32>, p: Params) -> vec3<f32> {
    return p.base * light_ambient;
}

// The engine calls this only for samples above the surface (l·n > 0) that
// reach the point.
fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    let n = f32(max(p.bands, 1u));
    let ln = dot(l.to_light, s.normal);
    let band = ceil(ln * n) / n;
    let h = normalize(l.to_light + s.to_eye);
    let lobe = pow(max(dot(h, s.normal), 0.0), p.shininess);
    let spot = select(0.0, 1.0, lobe > 0.5);
    return l.intensity * (p.base * l.diffuse * band + p.highlight * l.specular * spot);
}
