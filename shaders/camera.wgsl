// The camera as a view frustum. It sits at the origin (positions are
// camera-relative); `right` and `up` are pre-scaled by the half extents of the
// image plane at distance 1 (perspective) or of the window (orthographic).

// Mirrored by render::layout::Camera.
struct Camera {
    right: vec3<f32>,
    orthographic: u32,
    up: vec3<f32>,
    _pad0: u32,
    forward: vec3<f32>,
    _pad1: u32,
}

// The ray through point `sub` ((0.5, 0.5) is the centre) of pixel `px` of
// an image of `image_size` pixels; row 0 is the top of the image. The image
// size comes with each dispatch, so a preview at a lower resolution sees the
// same frustum.
fn primary_ray(cam: Camera, px: vec2<u32>, image_size: vec2<u32>, sub: vec2<f32>) -> Ray {
    let size = vec2<f32>(image_size);
    let ndc = vec2<f32>(
        (f32(px.x) + sub.x) / size.x * 2.0 - 1.0,
        1.0 - (f32(px.y) + sub.y) / size.y * 2.0,
    );
    let offset = ndc.x * cam.right + ndc.y * cam.up;
    if cam.orthographic != 0u {
        return make_ray(offset, cam.forward);
    }
    return make_ray(vec3<f32>(0.0), normalize(cam.forward + offset));
}
