//! The thin-lens camera against the lens formula: a point on the plane of focus stays sharp,
//! a point off it spreads over the predicted circle of confusion; and a zero aperture is the
//! pinhole, bit for bit.

mod common;

use common::{render, temp_dir, write_scene};
use rondo::Overrides;

/// Image side in pixels, vertical field of view in degrees, lens radius, focus distance.
const SIDE: u32 = 96;
const FOV: f64 = 30.0;
const APERTURE: f64 = 0.3;
const FOCUS: f64 = 5.0;

/// Renders a small lamp of radius `radius` on the axis at depth `z` through a camera with
/// `camera_extra` and returns the mean squared distance of its image from its centroid, in
/// pixels², weighted by brightness.
fn spread(z: f64, radius: f64, camera_extra: &str, name: &str) -> f64 {
    let dir = temp_dir(name);
    let scene = write_scene(
        &dir,
        "lens.ron",
        &format!(
            "Scene(camera: Camera(position: (0, 0, 0), look_at: (0, 0, 1), fov: {FOV}{camera_extra}), \
             settings: Settings(width: {SIDE}, height: {SIDE}, spp: 256, max_depth: 1), \
             materials: {{ \"lamp\": Light(emit: Constant((1, 1, 1))) }}, \
             entities: [Entity(material: \"lamp\", shape: Sphere(center: (0, 0, {z}), radius: {radius}))])"
        ),
    );
    let r = render(&scene, Overrides::default(), None);
    let pixels = r.film().mean();
    let mut sum = 0.0f64;
    let (mut cx, mut cy) = (0.0f64, 0.0f64);
    for (i, p) in pixels.iter().enumerate() {
        let w = f64::from(p.x);
        let (x, y) = ((i % SIDE as usize) as f64, (i / SIDE as usize) as f64);
        sum += w;
        cx += w * x;
        cy += w * y;
    }
    assert!(sum > 0.0, "the lamp is seen");
    let (cx, cy) = (cx / sum, cy / sum);
    pixels
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let (x, y) = ((i % SIDE as usize) as f64, (i / SIDE as usize) as f64);
            f64::from(p.x) * ((x - cx).powi(2) + (y - cy).powi(2))
        })
        .sum::<f64>()
        / sum
}

/// Size of a pixel on the plane of focus.
fn pixel_on_focus_plane() -> f64 {
    2.0 * FOCUS * (0.5 * FOV).to_radians().tan() / f64::from(SIDE)
}

#[test]
fn a_point_at_the_focus_distance_stays_sharp() {
    // Seen through the whole lens, a lamp 0.005 across on the plane of focus covers less than
    // a pixel: its image's RMS radius (the pixel's own ±½ included) stays below one pixel.
    let lens = format!(", aperture: {APERTURE}, focus_distance: {FOCUS}");
    let rms = spread(FOCUS, 0.005, &lens, "lens-sharp").sqrt();
    assert!(rms < 1.0, "in focus: RMS spread {rms} px");
}

#[test]
fn a_point_off_focus_spreads_over_the_circle_of_confusion() {
    // A point at depth z spreads over a disk of radius r·|1 − f/z| on the plane of focus
    // (similar triangles through the lens), whose mean squared radius is R²/2. The lamp's own
    // disk (radius s·f/z there) and the pixel's box (1/12 per axis) add their variances.
    let z = 2.5;
    let s = 0.03;
    let pitch = pixel_on_focus_plane();
    let coc = APERTURE * (1.0 - FOCUS / z).abs() / pitch;
    let lamp = s * FOCUS / z / pitch;
    let lens = format!(", aperture: {APERTURE}, focus_on: (0.4, -0.2, {FOCUS})");
    let m2 = spread(z, s, &lens, "lens-blur");
    let measured = (2.0 * (m2 - lamp * lamp / 2.0 - 1.0 / 6.0)).sqrt();
    assert!(
        (measured / coc - 1.0).abs() < 0.03,
        "circle of confusion {measured:.3} px, lens formula {coc:.3} px"
    );
    // The pinhole sees the same lamp sharp.
    let pinhole = spread(z, s, "", "lens-pinhole");
    assert!(
        (pinhole - lamp * lamp / 2.0 - 1.0 / 6.0).abs() < 0.1 * lamp * lamp,
        "pinhole spread {pinhole} vs the lamp's own {}",
        lamp * lamp / 2.0
    );
}

#[test]
fn a_zero_aperture_is_the_pinhole_bit_for_bit() {
    let dir = temp_dir("lens-zero");
    let source = |extra: &str| {
        format!(
            "Scene(camera: Camera(position: (0, 1, -4), look_at: (0, 0.5, 0){extra}), \
             settings: Settings(width: 24, height: 24, spp: 4), \
             materials: {{ \"w\": Diffuse(albedo: Constant((0.7, 0.7, 0.7))), \"l\": Light(emit: Constant((4, 4, 4))) }}, \
             entities: [Entity(material: \"w\", shape: Plane(point: (0, 0, 0), normal: (0, 1, 0))), \
                        Entity(material: \"l\", shape: Sphere(center: (0, 3, 0), radius: 0.5))])"
        )
    };
    let film = |extra: &str| {
        let scene = write_scene(&dir, "zero.ron", &source(extra));
        render(&scene, Overrides::default(), None).film().mean()
    };
    assert_eq!(film(""), film(", aperture: 0, focus_distance: 2"));
    assert_ne!(film(""), film(", aperture: 0.2, focus_distance: 2"));
}
