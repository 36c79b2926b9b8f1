//! KHR_texture_basisu (issue 39): BoxTextured's texture as KTX2 images
//! made by the Basis Universal encoder (UASTC and ETC1S,
//! tests/data/khronos/BoxTextured/README.md) decodes to the PNG's texels
//! within each codec's quality, and bad KTX2 images or extension objects
//! give one error naming the file's field.

use std::path::{Path, PathBuf};

use penumbra::loaders::gltf;
use serde_json::{json, Value};

fn boxes(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/khronos/BoxTextured")
        .join(name)
}

/// Peak signal-to-noise ratio of the colour channels, in dB.
fn psnr(a: &[[u8; 4]], b: &[[u8; 4]]) -> f64 {
    assert_eq!(a.len(), b.len());
    let se: f64 = a
        .iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |c| (f64::from(p[c]) - f64::from(q[c])).powi(2)))
        .sum();
    let mse = se / (3 * a.len()) as f64;
    10.0 * (255.0 * 255.0 / mse).log10()
}

#[test]
fn basisu_textures_decode_to_the_pngs_texels_within_their_codecs_quality() {
    let plain = gltf::read(&boxes("BoxTextured.gltf")).unwrap_or_else(|e| panic!("{e}"));
    let png = &plain.textures[0];
    // Basis Universal's quality: UASTC LDR is near-lossless (its encoder's
    // documentation gives 45–55 dB on typical images), ETC1S a low-bitrate
    // codec (about 30–40 dB). Rows read upside down or channels swapped
    // fall far below either.
    for (file, least) in [
        ("BoxTextured_basisu_uastc.gltf", 45.0),
        ("BoxTextured_basisu_etc1s.gltf", 30.0),
    ] {
        let doc = gltf::read(&boxes(file)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(doc.textures.len(), 1, "{file}");
        let t = &doc.textures[0];
        assert_eq!((t.width, t.height), (png.width, png.height), "{file}");
        let db = psnr(&t.texels, &png.texels);
        assert!(db >= least, "{file}: {db:.1} dB, below {least} dB");
    }
}

/// The error for BoxTextured_basisu_uastc.gltf changed by `change` (its
/// JSON and its KTX2 image's bytes), written with its image to a temporary
/// folder; the message is one line naming the file.
fn ktx2_error(change: impl FnOnce(&mut Value, &mut Vec<u8>)) -> String {
    let text = std::fs::read(boxes("BoxTextured_basisu_uastc.gltf")).unwrap();
    let mut json: Value = serde_json::from_slice(&text).unwrap();
    let mut ktx2 = std::fs::read(boxes("CesiumLogoFlat_uastc.ktx2")).unwrap();
    change(&mut json, &mut ktx2);
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("CesiumLogoFlat_uastc.ktx2"), ktx2).unwrap();
    let path = dir.path().join("box.gltf");
    std::fs::write(&path, serde_json::to_vec(&json).unwrap()).unwrap();
    let Err(err) = gltf::read(&path) else {
        panic!("expected an error")
    };
    let text = err.to_string();
    assert!(text.contains(&path.display().to_string()), "{text}");
    assert_eq!(text.lines().count(), 1, "{text}");
    text
}

#[test]
fn bad_ktx2_images_and_basisu_objects_name_the_field() {
    let cut = ktx2_error(|_, k| k.truncate(2000));
    assert!(cut.contains("images[0].uri: is a corrupt KTX2"), "{cut}");
    let garbled = ktx2_error(|_, k| {
        let n = k.len();
        k[n - 3000..].iter_mut().for_each(|b| *b ^= 0x5a);
    });
    assert!(garbled.contains("images[0].uri: "), "{garbled}");
    // vkFormat 37, VK_FORMAT_R8G8B8A8_UNORM: a KTX2 file, but not Basis Universal.
    let format = ktx2_error(|_, k| k[12..16].copy_from_slice(&37u32.to_le_bytes()));
    assert!(
        format.contains("images[0].uri: is a KTX2 image of format"),
        "{format}"
    );
    let mime = ktx2_error(|j, _| j["images"][0]["mimeType"] = json!("image/png"));
    assert!(
        mime.contains("images[0].uri: declares mimeType \"image/png\" but holds a KTX2 image"),
        "{mime}"
    );
    let png = ktx2_error(|_, k| *k = b"\x89PNG\r\n\x1a\n not really".to_vec());
    assert!(
        png.contains("images[0].uri: declares mimeType \"image/ktx2\" but is not a KTX2 file"),
        "{png}"
    );
    let source = ktx2_error(|j, _| {
        j["textures"][0]["extensions"]["KHR_texture_basisu"]["source"] = json!("zero")
    });
    assert!(
        source.contains(
            "textures[0].extensions.KHR_texture_basisu.source: must be the index of a KTX2 image"
        ),
        "{source}"
    );
    let dangling = ktx2_error(|j, _| {
        j["textures"][0]["extensions"]["KHR_texture_basisu"]["source"] = json!(5)
    });
    assert!(dangling.contains("images[5]: does not exist"), "{dangling}");
}
