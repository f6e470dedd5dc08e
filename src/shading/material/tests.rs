use super::*;
use crate::shading::rng::Rng;
use crate::shading::sampling::reflect;

#[test]
fn dielectric_reflects_four_percent_at_normal_incidence() {
    let glass = Material::glass(1.5);
    let mut rng = Rng::new(11, 13);
    let n = 1_000_000;
    let reflected = (0..n)
        .filter(|_| {
            let s = glass
                .scatter(-Vec3::Z, Vec3::Z, Vec2::ZERO, &mut rng)
                .expect("scatters");
            s.direction.z > 0.0
        })
        .count();
    let fraction = reflected as f64 / n as f64;
    assert!((fraction - 0.04).abs() < 0.001, "{fraction}");
}

#[test]
fn refraction_scales_radiance_by_the_squared_index_ratio() {
    // Along the camera path, entering glass (1 → 1.5) carries (1/1.5)², leaving it 1.5²;
    // reflection carries 1.
    let glass = Material::glass(1.5);
    let mut rng = Rng::new(4, 4);
    for (d, refracted) in [(-Vec3::Z, 1.0 / 2.25), (Vec3::Z, 2.25)] {
        for _ in 0..200 {
            let s = glass
                .scatter(d, Vec3::Z, Vec2::ZERO, &mut rng)
                .expect("scatters");
            let expected = if s.direction.dot(d) > 0.0 {
                refracted
            } else {
                1.0
            };
            assert!((s.attenuation - Vec3::splat(expected)).abs().max_element() < 1e-6);
        }
    }
}

#[test]
fn glass_to_air_beyond_the_critical_angle_always_reflects() {
    let glass = Material::glass(1.5);
    let critical = (1.0f32 / 1.5).asin();
    let mut rng = Rng::new(1, 2);
    for k in 1..=50 {
        let theta = critical + (std::f32::consts::FRAC_PI_2 - critical) * k as f32 / 51.0;
        // Inside the glass, travelling out through a surface whose normal points outwards (+z).
        let d = Vec3::new(theta.sin(), 0.0, theta.cos());
        for _ in 0..100 {
            let s = glass
                .scatter(d, Vec3::Z, Vec2::ZERO, &mut rng)
                .expect("scatters");
            assert!(
                s.direction.z < 0.0,
                "θ = {theta}: escaped along {}",
                s.direction
            );
        }
    }
}

#[test]
fn diffuse_never_scatters_a_zero_or_nan_direction() {
    let m = Material::Diffuse {
        albedo: Texture::Constant(Vec3::splat(0.5)),
    };
    let mut rng = Rng::new(5, 5);
    let n = Vec3::new(0.0, 1.0, 0.0);
    for _ in 0..100_000 {
        let s = m
            .scatter(-n, n, Vec2::ZERO, &mut rng)
            .expect("diffuse always scatters");
        assert!((s.direction.length() - 1.0).abs() < 1e-4 && s.direction.dot(n) >= 0.0);
    }
}

#[test]
fn diffuse_eval_matches_its_sampling_and_integrates_to_the_albedo() {
    let m = Material::Diffuse {
        albedo: Texture::Constant(Vec3::splat(0.6)),
    };
    let n = Vec3::Y;
    let d = Vec3::new(0.3, -1.0, 0.2).normalize();
    let mut rng = Rng::new(2, 3);
    let mut estimate = Vec3::ZERO;
    let count = 100_000;
    for _ in 0..count {
        let s = m.scatter(d, n, Vec2::ZERO, &mut rng).expect("scatters");
        let (f_cos, pdf) = m
            .bsdf_at(d, n, Vec2::ZERO)
            .eval(s.direction)
            .expect("evaluable");
        assert!((pdf - s.pdf.expect("pdf")).abs() < 1e-5);
        assert!((f_cos / pdf - s.attenuation).abs().max_element() < 1e-4);
        // Uniform hemisphere estimate of ∫ f cos dω = albedo (pdf 1/2π).
        let z = rng.next_f32();
        let phi = 2.0 * std::f32::consts::PI * rng.next_f32();
        let r = (1.0 - z * z).sqrt();
        let wi = Vec3::new(r * phi.cos(), z, r * phi.sin());
        estimate +=
            m.bsdf_at(d, n, Vec2::ZERO).eval(wi).expect("evaluable").0 * 2.0 * std::f32::consts::PI;
    }
    let mean = estimate / count as f32;
    assert!(
        (mean - Vec3::splat(0.6)).abs().max_element() < 0.01,
        "{mean}"
    );
    // Below the surface (on the far side from the viewer) the BSDF is zero.
    assert_eq!(
        m.bsdf_at(d, n, Vec2::ZERO).eval(-n),
        Some((Vec3::ZERO, 0.0))
    );
}

#[test]
fn metal_scatters_to_the_side_of_the_incoming_ray_or_absorbs() {
    let m = Material::Metal {
        albedo: Texture::Constant(Vec3::ONE),
        roughness: 1.0,
    };
    let mut rng = Rng::new(8, 1);
    let n = Vec3::Z;
    let d = Vec3::new(1.0, 0.0, -0.1).normalize();
    let mut absorbed = 0;
    for _ in 0..10_000 {
        match m.scatter(d, n, Vec2::ZERO, &mut rng) {
            Some(s) => assert!(s.direction.z > 0.0),
            None => absorbed += 1,
        }
    }
    assert!(
        absorbed > 0,
        "a grazing rough reflection loses some rays below the surface"
    );
    let smooth = Material::Metal {
        albedo: Texture::Constant(Vec3::ONE),
        roughness: 0.0,
    };
    let s = smooth.scatter(d, n, Vec2::ZERO, &mut rng).expect("mirror");
    assert!((s.direction - reflect(d, n)).length() < 1e-6);
}

#[test]
fn light_emits_only_on_its_front_side_unless_two_sided() {
    let one = Material::Light {
        emit: Texture::Constant(Vec3::ONE),
        intensity: 15.0,
        two_sided: false,
    };
    assert_eq!(
        one.emitted(-Vec3::Y, Vec3::Y, Vec2::ZERO),
        Vec3::splat(15.0)
    );
    assert_eq!(one.emitted(Vec3::Y, Vec3::Y, Vec2::ZERO), Vec3::ZERO);
    let two = Material::Light {
        emit: Texture::Constant(Vec3::ONE),
        intensity: 2.0,
        two_sided: true,
    };
    assert_eq!(two.emitted(Vec3::Y, Vec3::Y, Vec2::ZERO), Vec3::splat(2.0));
}

#[test]
fn a_textured_mix_picks_its_glass_with_the_weight_times_the_red_texel_at_the_point() {
    // Weight 0.6; red 0.25 on the checker's odd cells (uv (0, 0)), 1 on its even ones.
    // Over u stratified in [0, 1), the glass must come up 0.6 · red of the time, the
    // texture's opaque material 0.6 · (1 − red), the base 0.4, at each point.
    let pbr = |metallic| Material::pbr(Vec3::splat(0.5), metallic, 0.5);
    let mix = Material::Transmissive {
        weight: 0.6,
        glass: Box::new(Material::glass(1.5)),
        base: Box::new(pbr(0.5)),
        texture: Some(Box::new(TransmissionTexture {
            texture: Texture::Checker {
                scale: 10.0,
                even: Box::new(Texture::Constant(Vec3::new(1.0, 0.0, 0.0))),
                odd: Box::new(Texture::Constant(Vec3::new(0.25, 0.0, 0.0))),
            },
            opaque: pbr(0.0),
        })),
    };
    assert!(mix.reads_tex_coords());
    let n = 10_000;
    for (uv, red) in [(Vec2::ZERO, 0.25), (Vec2::new(0.15, 0.05), 1.0)] {
        let mut counts = [0usize; 3];
        for k in 0..n {
            let u = (k as f32 + 0.5) / n as f32;
            let picked = mix.component(uv, || u);
            let slot = match picked {
                Material::Dielectric { .. } => 0,
                Material::Pbr { metallic, .. } if *metallic == 0.0 => 1,
                _ => 2,
            };
            counts[slot] += 1;
        }
        let expected = [0.6 * red, 0.6 * (1.0 - red), 0.4];
        for (count, share) in counts.iter().zip(expected) {
            let got = *count as f64 / n as f64;
            assert!((got - share).abs() < 2e-4, "{uv}: {counts:?}, {expected:?}");
        }
    }
}

/// Every material kind with `texture` in each of its colour slots.
fn every_kind(texture: &Texture) -> Vec<Material> {
    vec![
        Material::Diffuse {
            albedo: texture.clone(),
        },
        Material::Metal {
            albedo: texture.clone(),
            roughness: 0.3,
        },
        Material::Glossy {
            albedo: texture.clone(),
            roughness: 0.4,
        },
        Material::Light {
            emit: texture.clone(),
            intensity: 3.0,
            two_sided: true,
        },
        Material::Pbr {
            base_color: texture.clone(),
            metallic: 0.5,
            roughness: 0.5,
            metallic_roughness: None,
            emissive: texture.clone(),
            emissive_strength: 1.0,
            normal_map: None,
            alpha: None,
            layers: Layers::NONE,
            layer_maps: None,
        },
    ]
}

#[test]
fn a_material_that_reads_no_coordinates_looks_the_same_at_every_point() {
    // What a hit reads of the material at `uv`: the BSDF's value, density and a sample,
    // the emission and the coverage.
    let look = |m: &Material, uv: Vec2| {
        let d = Vec3::new(0.3, 0.1, -1.0).normalize();
        let bsdf = m.bsdf(d, Vec3::Z, Vec3::Z, uv, || None);
        let sample = bsdf
            .sample(&mut Rng::new(5, 6))
            .map(|s| (s.direction, s.attenuation, s.pdf));
        let wi = Vec3::new(-0.2, 0.4, 0.8).normalize();
        (bsdf.eval(wi), sample, bsdf.emitted(), m.coverage(uv))
    };
    // The checker is odd at (0, 0) (sin 0 = 0) and even at the other two points.
    let uvs = [Vec2::ZERO, Vec2::new(0.15, 0.05), Vec2::new(0.05, 0.25)];
    let constant = Texture::Mapped(
        Box::new(Texture::Scaled(
            Box::new(Texture::Constant(Vec3::splat(0.6))),
            Vec3::new(1.0, 0.5, 0.25),
        )),
        Box::default(),
    );
    let mut plain = every_kind(&constant);
    plain.push(Material::glass(1.5));
    for m in &plain {
        assert!(!m.reads_tex_coords(), "{m:?}");
        for uv in uvs {
            assert_eq!(look(m, uv), look(m, uvs[0]), "{m:?} at {uv}");
        }
    }
    let checker = Texture::Checker {
        scale: 10.0,
        even: Box::new(Texture::Constant(Vec3::splat(0.9))),
        odd: Box::new(Texture::Constant(Vec3::splat(0.1))),
    };
    for m in every_kind(&checker) {
        assert!(m.reads_tex_coords(), "{m:?}");
        assert!(
            uvs.iter().any(|&uv| look(&m, uv) != look(&m, uvs[0])),
            "{m:?}"
        );
    }
}
