// `shade` must return vec3<f32>.
fn shade(s: Surface, l: LightSample, p: Params) -> f32 {
    return l.intensity;
}
