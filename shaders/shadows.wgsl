// Hard shadows: one shadow ray per light sample, with an any-hit early exit.
//
// Self-intersection ("shadow acne") is avoided without an epsilon that thin
// occluders could slip through:
// * a plane or triangle cannot shadow itself, so the shadow ray skips the
//   primitive it starts on;
// * a sphere shadows a point on itself exactly when the ray heads into it, and
//   then along the whole chord, so that case is decided analytically;
// * for a triangle hit, against every other primitive (neighbouring mesh
//   triangles) the origin is pushed off the surface by a few ULPs along the
//   geometric normal, as in Wächter and Binder, "A Fast and Robust Method for Avoiding
//   Self-Intersection" (Ray Tracing Gems, 2019). The offset scales with the
//   coordinates' magnitude, so it holds far from the origin too.

const OFFSET_ORIGIN: f32 = 1.0 / 32.0;
const OFFSET_FLOAT_SCALE: f32 = 1.0 / 65536.0;
// Wächter and Binder push by 256 ulps; our hit points are camera-relative
// (small, precise), and 256 ulps let light graze past folds of a mesh that
// the f64 reference shows in shadow (68 of the bunny scene's 1024² pixels);
// 32 ulps leave 10 and no acne in tests/render_shadows.rs.
const OFFSET_INT_SCALE: f32 = 32.0;

fn offset_ray_origin(p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let of_i = vec3<i32>(OFFSET_INT_SCALE * n);
    let p_i = bitcast<vec3<f32>>(bitcast<vec3<i32>>(p) + select(of_i, -of_i, p < vec3<f32>(0.0)));
    return select(p_i, p + OFFSET_FLOAT_SCALE * n, abs(p) < vec3<f32>(OFFSET_ORIGIN));
}

// Whether anything blocks the light in unit direction `to_light` at
// distance `t_max` from the hit point.
fn occluded(hit: Hit, to_light: vec3<f32>, t_max: f32) -> bool {
    // (The shadow stage traces only samples above the geometric surface.)
    // Only triangles need the offset (their neighbours): planes and spheres
    // never intersect themselves here, and an offset of many ulps of the
    // camera-relative position would shift their shadows, and let light leak
    // under thin occluders seen from afar.
    var origin = hit.position;
    var start = hit;
    if SHADOW_EPSILON > 0.0 {
        // The classic alternative (render::ShadowOffset::Fixed): a fixed
        // offset along the normal and no knowledge of where the ray starts.
        origin += SHADOW_EPSILON * hit.geometric_normal;
        start.kind = KIND_NONE;
    } else if hit.kind == KIND_TRIANGLE {
        origin = offset_ray_origin(hit.position, hit.geometric_normal);
    }
    let ray = make_ray(origin, to_light);
    if HAS_PLANES {
        for (var i = 0u; i < globals.num_planes; i++) {
            if start.kind == KIND_PLANE && start.index == i {
                continue;
            }
            let t = intersect_plane(planes[i], ray);
            if t > 0.0 && t < t_max {
                return true;
            }
        }
    }
    if USE_BVH {
        return bvh_occluded(ray, t_max, start);
    }
    if HAS_SPHERES {
        for (var i = 0u; i < globals.num_spheres; i++) {
            if sphere_blocks(i, ray, t_max, start) {
                return true;
            }
        }
    }
    if HAS_TRIANGLES {
        for (var i = 0u; i < globals.num_triangles; i++) {
            if triangle_blocks(i, ray, t_max, start) {
                return true;
            }
        }
    }
    return false;
}

// Whether sphere `i` blocks the shadow ray that leaves `start`.
fn sphere_blocks(i: u32, ray: Ray, t_max: f32, start: Hit) -> bool {
    let sphere = spheres[i];
    if start.kind == KIND_SPHERE && start.index == i {
        // Its own sphere blocks exactly when the ray heads inside, along the
        // chord 2·l·(c − p).
        let into = dot(ray.dir, sphere.center - start.position);
        return into > 0.0 && 2.0 * into < t_max;
    }
    let roots = sphere_roots(sphere, ray);
    // Either root inside (0, t_max) blocks; a ray starting inside a sphere is
    // blocked by its far side.
    return roots.x <= roots.y && ((roots.x > 0.0 && roots.x < t_max) || (roots.y > 0.0 && roots.y < t_max));
}

// Whether triangle `i` blocks the shadow ray that leaves `start` (never the
// triangle it starts on).
fn triangle_blocks(i: u32, ray: Ray, t_max: f32, start: Hit) -> bool {
    if start.kind == KIND_TRIANGLE && start.index == i {
        return false;
    }
    let tri = triangle(i);
    let h = intersect_triangle(tri, ray, t_max);
    return h.x > 0.0 && triangle_is_there(i, tri, h.yz);
}
