// Defines only `ambient`: `shade` is missing.
fn ambient(s: Surface, light_ambient: vec3<f32>, p: Params) -> vec3<f32> {
    return light_ambient;
}
