// A user shader with a texture parameter (scenes/textured.json): the
// texture's colour at the point, tinted, times a Lambert term, plus a
// little of the light's ambient colour. `albedo` is given in the scene as
// {"texture": "..."}: the engine's texture_at samples it at the point's
// texture coordinates (a sphere's latitude-longitude ones here), filtered
// as the scene says.

struct Params {
    albedo: u32,
    tint: vec3<f32>,
}

fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    let c = texture_at(p.albedo, s).rgb * p.tint;
    return c * l.diffuse * l.intensity * max(dot(s.normal, l.to_light), 0.0);
}

fn ambient(s: Surface, light_ambient: vec3<f32>, p: Params) -> vec3<f32> {
    return texture_at(p.albedo, s).rgb * p.tint * light_ambient;
}
