//! Vertex attribute component types: glTF 2.0's own, and the integer
//! types KHR_mesh_quantization adds for POSITION, NORMAL, TANGENT and
//! TEXCOORD_n (and morph target displacements), dequantized as glTF
//! specifies.
//!
//! KHR_mesh_quantization, "Extending Mesh Attributes": POSITION may be
//! (unsigned) byte or short, normalized or not; NORMAL and TANGENT
//! normalized byte or short; TEXCOORD_n (unsigned) byte or short,
//! normalized or not. glTF 2.0 §3.11 ("Animations", normalized
//! integers): a normalized signed value `c` means `max(c / (2^(b-1) - 1), -1)`,
//! an unsigned one `c / (2^b - 1)`; an integer that is not normalized is
//! its own value.

use gltf::accessor::DataType;

/// A vertex attribute whose component type this module checks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Attribute {
    Position,
    Normal,
    Tangent,
    TexCoord,
    /// A morph target's POSITION displacement.
    PositionDelta,
    /// A morph target's NORMAL displacement.
    NormalDelta,
    /// EXT_mesh_gpu_instancing's TRANSLATION and SCALE.
    InstanceVector,
    /// EXT_mesh_gpu_instancing's ROTATION (a quaternion).
    InstanceRotation,
}

use DataType::{F32, I16, I8, U16, U8};

/// (component type, normalized) pairs allowed for `attribute`; `quantized`
/// when the file uses KHR_mesh_quantization.
pub(super) fn allowed(attribute: Attribute, quantized: bool) -> &'static [(DataType, bool)] {
    use Attribute::*;
    const FLOAT: &[(DataType, bool)] = &[(F32, false)];
    const UV: &[(DataType, bool)] = &[(F32, false), (U8, true), (U16, true)];
    const SIGNED_NORM: &[(DataType, bool)] = &[(F32, false), (I8, true), (I16, true)];
    const ANY_INT: &[(DataType, bool)] = &[
        (F32, false),
        (I8, false),
        (I8, true),
        (U8, false),
        (U8, true),
        (I16, false),
        (I16, true),
        (U16, false),
        (U16, true),
    ];
    const DELTA: &[(DataType, bool)] = &[
        (F32, false),
        (I8, false),
        (I8, true),
        (I16, false),
        (I16, true),
    ];
    match (attribute, quantized) {
        (TexCoord, false) => UV,
        (InstanceRotation, _) => SIGNED_NORM,
        // EXT_mesh_gpu_instancing allows these types with quantization.
        (InstanceVector, true) => DELTA,
        (_, false) => FLOAT,
        (Position | TexCoord, true) => ANY_INT,
        (Normal | Tangent | NormalDelta, true) => SIGNED_NORM,
        (PositionDelta, true) => DELTA,
    }
}

/// The glTF name of `(ty, normalized)`, e.g. `normalized SHORT`.
pub(super) fn name((ty, normalized): (DataType, bool)) -> String {
    let base = match ty {
        I8 => "BYTE",
        U8 => "UNSIGNED_BYTE",
        I16 => "SHORT",
        U16 => "UNSIGNED_SHORT",
        DataType::U32 => "UNSIGNED_INT",
        F32 => "FLOAT",
    };
    match normalized {
        true => format!("normalized {base}"),
        false => base.to_string(),
    }
}

/// Turns the components read from an accessor of type `ty` into the
/// numbers they stand for (see the module's documentation).
pub(super) fn dequantize(values: &mut [f64], ty: DataType, normalized: bool) {
    if !normalized {
        return;
    }
    let (max, signed) = match ty {
        I8 => (127.0, true),
        U8 => (255.0, false),
        I16 => (32767.0, true),
        U16 => (65535.0, false),
        DataType::U32 => (4294967295.0, false),
        F32 => return,
    };
    for v in values.iter_mut() {
        *v /= max;
        if signed {
            *v = v.max(-1.0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalized_integers_follow_the_gltf_formulas() {
        let mut v = [-128.0, -127.0, 0.0, 127.0];
        dequantize(&mut v, I8, true);
        assert_eq!(v, [-1.0, -1.0, 0.0, 1.0]);
        let mut v = [0.0, 51.0, 255.0];
        dequantize(&mut v, U8, true);
        assert_eq!(v, [0.0, 0.2, 1.0]);
        let mut v = [-32768.0, 16384.0];
        dequantize(&mut v, I16, true);
        assert_eq!(v, [-1.0, 16384.0 / 32767.0]);
        let mut v = [-5.0, 300.0];
        dequantize(&mut v, I16, false);
        assert_eq!(v, [-5.0, 300.0]);
    }

    #[test]
    fn quantized_types_need_the_extension() {
        assert_eq!(allowed(Attribute::Position, false), &[(F32, false)]);
        assert!(allowed(Attribute::Position, true).contains(&(U16, false)));
        assert!(!allowed(Attribute::Normal, true).contains(&(I16, false)));
        assert!(allowed(Attribute::Normal, true).contains(&(I8, true)));
        assert!(allowed(Attribute::TexCoord, false).contains(&(U8, true)));
        assert!(!allowed(Attribute::TexCoord, false).contains(&(U8, false)));
        assert!(allowed(Attribute::TexCoord, true).contains(&(I16, false)));
    }
}
