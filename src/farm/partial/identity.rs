//! A partial's identity: the settings text that says how its pixels were made, and the hash of
//! everything else they depend on. Partials merge or resume only when both agree.

use std::path::PathBuf;

use super::meta::{FORMAT, PartialError, error};
use crate::scene::bounded_read::{MAX_INPUT_BYTES, read_bounded};
use crate::scene::format::{Method, SettingsDesc};
use crate::shading::sampler::SamplerKind;

/// 64-bit FNV-1a, a stable hash (unlike std's, whose algorithm may change).
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
    fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    fn field(&mut self, bytes: &[u8]) {
        self.bytes(&(bytes.len() as u64).to_le_bytes());
        self.bytes(bytes);
    }
}

/// How a renderer traces, beyond the scene's settings, where it changes an image's bits
/// (thread count and geometry layout never do, so they are not here).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tracing {
    /// Russian roulette on ([`crate::Renderer::set_roulette`]).
    pub roulette: bool,
    /// Meshes placed as instances ([`crate::Renderer::set_instancing`]).
    pub instancing: bool,
}

impl Default for Tracing {
    /// What `rondo render` does: roulette and instancing on.
    fn default() -> Self {
        Self {
            roulette: true,
            instancing: true,
        }
    }
}

/// The keys of [`image_settings`], in order.
const SETTING_KEYS: [&str; 6] = [
    "max_depth",
    "method",
    "sampler",
    "background",
    "roulette",
    "instancing",
];

/// Every setting besides the size, seed and samples that changes an image's pixels, as words
/// `key=value` in a fixed order: `max_depth=8 method=mis sampler=sobol background=0,0,0
/// roulette=on instancing=on`. Stored as a partial's `rondo.settings` and hashed, so partials
/// of renders that differ in any of them neither merge nor resume, and the refusal names it.
pub fn image_settings(settings: &SettingsDesc, tracing: Tracing) -> String {
    // Every field by name: a setting added to `SettingsDesc` fails to compile here until it is
    // either part of a partial's identity or known to leave the pixels alone.
    let SettingsDesc {
        width: _,
        height: _,
        spp: _,
        max_depth,
        background,
        seed: _,
        method,
        sampler,
        denoise: _,
        // The environment's and the sun's parameters are in the scene file's text, and the
        // map's pixels in its file: both are dependencies, hashed by `image_hash`.
        environment: _,
        sun: _,
    } = settings;
    let Tracing {
        roulette,
        instancing,
    } = tracing;
    let on = |b: bool| if b { "on" } else { "off" };
    // `{}` of an f32 is the shortest text that reads back to the same bits.
    format!(
        "max_depth={max_depth} method={method} sampler={sampler} background={},{},{} roulette={} instancing={}",
        background.x,
        background.y,
        background.z,
        on(roulette),
        on(instancing)
    )
}

/// The first setting two [`image_settings`] texts differ in: its key and both values.
pub fn setting_difference<'a>(a: &'a str, b: &'a str) -> Option<(&'a str, &'a str, &'a str)> {
    a.split(' ').zip(b.split(' ')).find_map(|(x, y)| {
        let (key, mine) = x.split_once('=')?;
        let theirs = y.strip_prefix(key)?.strip_prefix('=')?;
        (mine != theirs).then_some((key, mine, theirs))
    })
}

/// Checks a `rondo.settings` text: the keys of [`image_settings`] in its order, each value
/// well-formed and within the limits a render accepts; gives the `max_depth`.
pub(super) fn check_settings(text: &str) -> Result<u32, String> {
    let words: Vec<&str> = text.split(' ').collect();
    if words.len() != SETTING_KEYS.len() {
        return Err(format!("expected the keys {}", SETTING_KEYS.join(", ")));
    }
    let mut values = [""; SETTING_KEYS.len()];
    for ((word, key), value) in words.iter().zip(SETTING_KEYS).zip(&mut values) {
        *value = word
            .strip_prefix(key)
            .and_then(|v| v.strip_prefix('='))
            .ok_or_else(|| format!("expected {key}=… where {word:?} is"))?;
    }
    let [max_depth, method, sampler, background, roulette, instancing] = values;
    let max_depth: u32 = max_depth
        .parse()
        .map_err(|_| format!("max_depth {max_depth:?} is not a whole number"))?;
    let method: Method = method.parse()?;
    let sampler: SamplerKind = sampler.parse()?;
    let background: Vec<f32> = background
        .split(',')
        .map(|c| c.parse::<f32>().ok().filter(|c| c.is_finite()))
        .collect::<Option<_>>()
        .filter(|b: &Vec<f32>| b.len() == 3)
        .ok_or_else(|| format!("background {background:?} is not three finite numbers"))?;
    let flag = |key: &str, v: &str| match v {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err(format!("{key} {v:?} is neither on nor off")),
    };
    let settings = SettingsDesc {
        max_depth,
        background: glam::Vec3::new(background[0], background[1], background[2]),
        method,
        sampler,
        ..SettingsDesc::default()
    };
    settings.validate()?;
    let tracing = Tracing {
        roulette: flag("roulette", roulette)?,
        instancing: flag("instancing", instancing)?,
    };
    // One text per identity, so that comparing texts compares settings.
    if image_settings(&settings, tracing) != text {
        return Err("not in the canonical form rondo writes".into());
    }
    Ok(max_depth)
}

/// Hash of everything an image depends on but the sample range: the format, rondo's version,
/// the contents of every file the scene loads (the scene file first, in load order; paths are
/// left out, so the same scene in another directory hashes the same), the size, the seed and
/// the [`image_settings`] text `settings`.
pub fn image_hash(
    dependencies: &[PathBuf],
    size: (u32, u32),
    seed: u64,
    settings: &str,
) -> Result<u64, PartialError> {
    let mut h = Fnv::new();
    h.field(FORMAT.as_bytes());
    h.field(env!("CARGO_PKG_VERSION").as_bytes());
    for path in dependencies {
        let (_, data) = read_bounded(path, MAX_INPUT_BYTES)
            .map_err(|e| error(path, format!("cannot read: {e}")))?;
        h.field(&data);
    }
    h.field(&size.0.to_le_bytes());
    h.field(&size.1.to_le_bytes());
    h.field(&seed.to_le_bytes());
    h.field(settings.as_bytes());
    Ok(h.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_text_reads_back_only_in_its_canonical_form() {
        let s = SettingsDesc {
            background: glam::Vec3::new(0.1, 1e-10, 5e9),
            method: Method::Mis,
            sampler: SamplerKind::Independent,
            ..SettingsDesc::default()
        };
        let off = Tracing {
            roulette: false,
            ..Tracing::default()
        };
        let text = image_settings(&s, off);
        assert_eq!(
            text,
            "max_depth=8 method=mis sampler=independent background=0.1,0.0000000001,5000000000 roulette=off instancing=on"
        );
        assert_eq!(check_settings(&text), Ok(8));
        let on = image_settings(&s, Tracing::default());
        assert_eq!(
            setting_difference(&text, &on),
            Some(("roulette", "off", "on"))
        );
        for bad in [
            "",
            "max_depth=8",
            &text.replace("max_depth=8", "max_depth=08"),
            &text.replace("max_depth=8", "max_depth=2000"),
            &text.replace("sampler=independent", "sampler=halton"),
            &text.replace("0.1,", "NaN,"),
            &text.replace(" roulette", "  roulette"),
            &text.replace("roulette=off", "roulette=no"),
        ] {
            assert!(check_settings(bad).is_err(), "{bad:?}");
        }
    }
}
