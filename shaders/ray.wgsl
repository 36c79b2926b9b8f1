// A ray: origin and unit direction, and what the watertight triangle test
// needs of it, computed once per ray (Woop, Benthin and Wald, "Watertight
// Ray/Triangle Intersection", JCGT 2013): the axis along which |dir| is
// largest (kz), the two others (kx, ky, swapped when dir[kz] < 0 to keep the
// winding), and the shear that maps dir onto +z.

// Which ray/triangle test the kernel uses (render::TriangleTest; the tests
// are in primitives/triangle.wgsl). The watertight one needs the shear below.
const TRIANGLE_UV_FIRST: u32 = 0u;
const TRIANGLE_T_FIRST: u32 = 1u;
const TRIANGLE_WATERTIGHT: u32 = 2u;

struct Ray {
    origin: vec3<f32>,
    dir: vec3<f32>,
    axes: vec3<u32>,
    shear: vec3<f32>,
}

fn make_ray(origin: vec3<f32>, dir: vec3<f32>) -> Ray {
    var ray: Ray;
    ray.origin = origin;
    ray.dir = dir;
    if TRIANGLE_TEST == TRIANGLE_WATERTIGHT {
        let a = abs(dir);
        var kz = 2u;
        if a.x > a.y && a.x > a.z {
            kz = 0u;
        } else if a.y > a.z {
            kz = 1u;
        }
        var kx = (kz + 1u) % 3u;
        var ky = (kx + 1u) % 3u;
        if dir[kz] < 0.0 {
            let swap = kx;
            kx = ky;
            ky = swap;
        }
        ray.axes = vec3<u32>(kx, ky, kz);
        ray.shear = vec3<f32>(dir[kx] / dir[kz], dir[ky] / dir[kz], 1.0 / dir[kz]);
    }
    return ray;
}

fn ray_at(ray: Ray, t: f32) -> vec3<f32> {
    return ray.origin + t * ray.dir;
}
