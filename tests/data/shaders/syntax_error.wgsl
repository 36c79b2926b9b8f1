// A missing expression on line 4.
fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    let d = max(dot(s.normal, l.to_light), 0.0);
    let q = ;
    return vec3(d);
}
