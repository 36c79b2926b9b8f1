// Normal visualiser: the unit shading normal n (world axes, facing the
// viewer) shown as the colour 0.5·n + 0.5, the same lit or in shadow.
//
// The colour comes from `ambient`, which the engine adds once per light:
// set `weight` to 1 / (number of lights) for the plain mapping.

struct Params {
    weight: f32,
}

fn ambient(s: Surface, light_ambient: vec3<f32>, p: Params) -> vec3<f32> {
    return p.weight * (0.5 * s.normal + vec3<f32>(0.5));
}

fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    return vec3<f32>(0.0);
}
