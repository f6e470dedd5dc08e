//! The exact Fresnel reflectance of unpolarised light at a dielectric interface, as both glass
//! lobes ([`super::dielectric`], [`super::rough_dielectric`]) use it. No ECS here.
//!
//! Reference: Born & Wolf, "Principles of Optics", §1.5.2 (the Fresnel equations); pbrt-v4's
//! `FrDielectric` (`src/pbrt/util/scattering.h`) takes the same arguments. Against Schlick's
//! approximation, which rondo's glass used before, the exact curve reflects more at oblique
//! incidence (0.0892 against 0.0700 at 60° for n = 1.5), so glass looks slightly brighter at its
//! rim (a glass ball under a sky gains about 0.5 % of mean radiance, as Mitsuba's exact one does).

/// Fresnel reflectance of unpolarised light arriving at cosine `cos_i` (measured on the side the
/// light comes from, in [0, 1]) at an interface of relative index `eta` = n_t / n_i (the index
/// beyond the interface over the index the light comes from): the mean of the squared s- and
/// p-polarised amplitude ratios, 1 beyond the critical angle (total internal reflection).
#[inline]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_parallel * r_parallel + r_perpendicular * r_perpendicular)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Fresnel equations in angle form (Born & Wolf 1.5 (21a)–(21b)), in `f64`:
    /// R_s = sin²(θi − θt) / sin²(θi + θt), R_p = tan²(θi − θt) / tan²(θi + θt).
    fn by_angles(theta_i: f64, n_i: f64, n_t: f64) -> f64 {
        let sin_t = n_i / n_t * theta_i.sin();
        if sin_t >= 1.0 {
            return 1.0;
        }
        let theta_t = sin_t.asin();
        let (minus, plus) = (theta_i - theta_t, theta_i + theta_t);
        let rs = (minus.sin() / plus.sin()).powi(2);
        let rp = (minus.tan() / plus.tan()).powi(2);
        0.5 * (rs + rp)
    }

    #[test]
    fn matches_the_angle_form_of_the_fresnel_equations_both_ways() {
        for (n_i, n_t) in [(1.0, 1.5), (1.5, 1.0), (1.0, 1.33), (2.4, 1.0), (1.0, 0.8)] {
            for deg in [1.0f64, 10.0, 30.0, 45.0, 60.0, 75.0, 85.0, 89.0] {
                let theta = deg.to_radians();
                let exact = by_angles(theta, n_i, n_t);
                let got = fresnel_dielectric(theta.cos() as f32, (n_t / n_i) as f32);
                assert!(
                    (f64::from(got) - exact).abs() < 2e-5,
                    "{n_i} → {n_t} at {deg}°: {got} against {exact}"
                );
            }
        }
    }

    #[test]
    fn normal_incidence_grazing_and_total_internal_reflection() {
        // ((n − 1)/(n + 1))² at normal incidence, from either side.
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((fresnel_dielectric(1.0, 1.0 / 1.5) - 0.04).abs() < 1e-6);
        assert!((fresnel_dielectric(0.0, 1.5) - 1.0).abs() < 1e-6);
        // Glass → air: the critical angle is asin(1/1.5) ≈ 41.81°; just below, R < 1; beyond, 1.
        let critical = (1.0f32 / 1.5).asin();
        assert!(fresnel_dielectric((critical - 0.01).cos(), 1.0 / 1.5) < 1.0);
        for deg in [42.0f32, 50.0, 70.0, 89.9] {
            assert_eq!(fresnel_dielectric(deg.to_radians().cos(), 1.0 / 1.5), 1.0);
        }
        // The same interface reflects the same share both ways at Snell-related angles.
        let theta_i = 0.6f32;
        let theta_t = (theta_i.sin() / 1.5).asin();
        let a = fresnel_dielectric(theta_i.cos(), 1.5);
        let b = fresnel_dielectric(theta_t.cos(), 1.0 / 1.5);
        assert!((a - b).abs() < 1e-6, "{a} {b}");
    }
}
