// No Params: the normal as a colour, lit by each light sample.
fn shade(s: Surface, l: LightSample, p: Params) -> vec3<f32> {
    return (s.normal * 0.5 + vec3(0.5)) * l.intensity * max(dot(s.normal, l.to_light), 0.0);
}
