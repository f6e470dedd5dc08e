//! Images whose header declares more texels than rondo accepts are refused from the header,
//! before their pixels are allocated: a counting allocator measures the most bytes held at once
//! while each file is refused, against the gigabyte its pixels would take.

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::io::Write;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, MutexGuard};

use common::gltf_doc::{Bin, glb};
use common::{temp_dir, write_scene};
use rondo::scene::assets::AssetCache;
use rondo::scene::load::load_scene;
use serde_json::json;

/// The system allocator, counting the bytes held and the most held at once.
struct Counting;

static HELD: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

// SAFETY: every call is forwarded to `System` with its own arguments; the counters only
// observe the sizes.
#[expect(
    unsafe_code,
    reason = "a global allocator is an unsafe trait; it forwards to System"
)]
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let held = HELD.fetch_add(layout.size(), Ordering::SeqCst) + layout.size();
        PEAK.fetch_max(held, Ordering::SeqCst);
        // SAFETY: the caller's contract for `alloc` is passed on unchanged.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let held = HELD.fetch_add(layout.size(), Ordering::SeqCst) + layout.size();
        PEAK.fetch_max(held, Ordering::SeqCst);
        // SAFETY: as `alloc`.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        HELD.fetch_sub(layout.size(), Ordering::SeqCst);
        // SAFETY: `ptr` was allocated by `System` with `layout`.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if new_size > layout.size() {
            let grown = new_size - layout.size();
            let held = HELD.fetch_add(grown, Ordering::SeqCst) + grown;
            PEAK.fetch_max(held, Ordering::SeqCst);
        } else {
            HELD.fetch_sub(layout.size() - new_size, Ordering::SeqCst);
        }
        // SAFETY: as `dealloc` and `alloc`.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Held by each test from its start: the counters are global to the test binary, so no other
/// test may allocate while one measures.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// Waits for the other tests to finish.
fn alone() -> MutexGuard<'static, ()> {
    ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// `f`'s result and the most bytes it held at once beyond what was held when it started (call
/// while holding [`alone`]).
fn peak_during<T>(f: impl FnOnce() -> T) -> (T, usize) {
    let start = HELD.load(Ordering::SeqCst);
    PEAK.store(start, Ordering::SeqCst);
    let out = f();
    (out, PEAK.load(Ordering::SeqCst).saturating_sub(start))
}

/// Most bytes a refusal may hold: the file, the decoder's state, the scene's parse, far below
/// the pixels of any of these images (≥ 800 MB).
const REFUSAL_BYTES: usize = 32 << 20;

/// A valid 1-bit greyscale PNG of `side`² black texels (about 130 KB for 32768²: its rows are
/// all zero and compress well), 1 GiB once decoded to 8 bits per texel.
fn bomb_png(side: u32) -> Vec<u8> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, side, side);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::One);
    encoder.set_compression(png::Compression::Best);
    let mut writer = encoder.write_header().expect("header");
    let mut stream = writer.stream_writer().expect("stream");
    let row = vec![0u8; side.div_ceil(8) as usize];
    for _ in 0..side {
        stream.write_all(&row).expect("row");
    }
    stream.finish().expect("finish");
    writer.finish().expect("end");
    out
}

/// A 115-byte Radiance `.hdr` whose header declares `side`² texels, followed by a few bytes of
/// its first scanline: 768 MB of RGB floats for 8192².
fn bomb_hdr(side: u32) -> Vec<u8> {
    let mut out =
        format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {side} +X {side}\n").into_bytes();
    out.extend([2, 2, 0x20, 0]);
    out.resize(115, 0);
    out
}

#[test]
fn a_png_texture_declaring_too_many_texels_is_refused_before_its_pixels_are_allocated() {
    let _alone = alone();
    let dir = temp_dir("bomb-png");
    let path = dir.join("bomb.png");
    std::fs::write(&path, bomb_png(32768)).expect("write");
    let (result, peak) = peak_during(|| AssetCache::default().texture(&path).map(|_| ()));
    let e = result.expect_err("a 32768² texture is refused");
    assert!(e.contains("32768×32768 texels; at most 268435456"), "{e}");
    assert!(peak < REFUSAL_BYTES, "{peak} bytes held while refusing");
}

#[test]
fn an_hdr_environment_declaring_too_many_texels_is_refused_before_its_pixels_are_allocated() {
    let _alone = alone();
    let dir = temp_dir("bomb-hdr");
    let path = dir.join("sky.hdr");
    let bytes = bomb_hdr(8192);
    assert_eq!(bytes.len(), 115);
    std::fs::write(&path, &bytes).expect("write");
    let (result, peak) = peak_during(|| AssetCache::default().environment(&path).map(|_| ()));
    let e = result.expect_err("an 8192² map is refused");
    assert!(e.contains("8192×8192 texels; at most 33554432"), "{e}");
    assert!(peak < REFUSAL_BYTES, "{peak} bytes held while refusing");
    // The decoder alone, as `rondo bench environment` calls it.
    let (_, direct) =
        peak_during(|| AssetCache::decode_environment_pixels(Path::new("x.hdr"), &bytes));
    assert!(direct < REFUSAL_BYTES, "{direct} bytes held while refusing");
}

#[test]
fn a_truncated_hdr_environment_is_refused_before_its_pixels_are_allocated() {
    let _alone = alone();
    // 8192 × 4096: exactly the largest map accepted, 400 MB of RGB floats, in 115 bytes.
    let mut bytes = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4096 +X 8192\n".to_vec();
    bytes.extend([2, 2, 0x20, 0]);
    bytes.resize(115, 0);
    let (result, peak) =
        peak_during(|| AssetCache::decode_environment_pixels(Path::new("x.hdr"), &bytes));
    let e = result.expect_err("a truncated map is refused");
    assert!(
        e.contains("8192×4096 texels") && e.contains("truncated"),
        "{e}"
    );
    assert!(peak < REFUSAL_BYTES, "{peak} bytes held while refusing");
}

#[test]
fn an_image_embedded_in_a_glb_declaring_too_many_texels_is_refused_before_decoding() {
    let _alone = alone();
    let dir = temp_dir("bomb-glb");
    let mut bin = Bin::default();
    let v = bin.f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let uv = bin.f32s(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0]);
    let image = bin.view(bomb_png(32768));
    let parts = json!({
        "accessors": [
            {"bufferView": v, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": uv, "componentType": 5126, "count": 3, "type": "VEC2"},
        ],
        "images": [{"bufferView": image, "mimeType": "image/png"}],
        "textures": [{"source": 0}],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": 0}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
    });
    std::fs::write(dir.join("bomb.glb"), glb(&bin, parts)).expect("write");
    let scene = write_scene(
        &dir,
        "scene.ron",
        r#"Scene(camera: Camera(position: (0, 0, 2), look_at: (0, 0, 0)),
                 entities: [Entity(name: "m", gltf: "bomb.glb")])"#,
    );
    let (result, peak) = peak_during(|| {
        load_scene(&scene, &mut AssetCache::default())
            .map(|_| ())
            .map_err(|e| e.to_string())
    });
    let e = result.expect_err("the embedded image is refused");
    assert!(e.contains("32768×32768 texels"), "{e}");
    assert!(peak < REFUSAL_BYTES, "{peak} bytes held while refusing");
}

#[test]
fn an_image_to_compare_declaring_more_pixels_than_a_render_is_refused_from_its_header() {
    let _alone = alone();
    let dir = temp_dir("bomb-diff");
    let path = dir.join("bomb.png");
    std::fs::write(&path, bomb_png(32768)).expect("write");
    let (result, peak) = peak_during(|| rondo::metrics::Image::read(&path).map(|_| ()));
    match result {
        Err(rondo::metrics::MetricsError::TooLarge { size, .. }) => {
            assert_eq!(size, (32768, 32768));
        }
        other => panic!("refused as too large, not {other:?}"),
    }
    assert!(peak < REFUSAL_BYTES, "{peak} bytes held while refusing");
}
