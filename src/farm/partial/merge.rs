//! Merging partials: the checks that they belong to one render, then the sums added.

use std::ops::Range;
use std::path::{Path, PathBuf};

use super::identity::setting_difference;
use super::meta::{FORMAT_2, PartialError, PartialMeta, Sums, error};
use super::ranges::{gaps, normalize};
use super::read::{add_partial, read_meta};

/// What a merge found: the combined metadata and the samples missing below its end.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MergePlan {
    /// Metadata of the merged result.
    pub meta: PartialMeta,
    /// Samples of `0..end` held by no input.
    pub missing: Vec<Range<u32>>,
}

/// Checks that the partials at `paths` can merge: same size, seed, fixed-point shift, settings,
/// format (all with the feature buffers, or all without) and image hash, no sample in two of
/// them. Gaps (up to `expect_end` if given, else up to the last sample held) are reported in the
/// plan, not refused here.
pub fn plan_merge(paths: &[PathBuf], expect_end: Option<u32>) -> Result<MergePlan, PartialError> {
    let Some(first_path) = paths.first() else {
        return Err(PartialError("merge: no partials given".into()));
    };
    let metas = paths
        .iter()
        .map(|p| read_meta(p))
        .collect::<Result<Vec<_>, _>>()?;
    let first = &metas[0];
    let mut owned: Vec<(Range<u32>, &Path)> = Vec::new();
    for (meta, path) in metas.iter().zip(paths) {
        let differs = |what: &str, mine: String, theirs: String| {
            Err(error(
                path,
                format!(
                    "{what} {mine}, but {} has {what} {theirs}: partials of one render only",
                    first_path.display()
                ),
            ))
        };
        if (meta.width, meta.height) != (first.width, first.height) {
            return differs(
                "resolution",
                format!("{}x{}", meta.width, meta.height),
                format!("{}x{}", first.width, first.height),
            );
        }
        if meta.seed != first.seed {
            return differs("seed", meta.seed.to_string(), first.seed.to_string());
        }
        if meta.shift != first.shift {
            return differs(
                "fraction bits",
                meta.shift.to_string(),
                first.shift.to_string(),
            );
        }
        if meta.features && first.features && meta.albedo_shift != first.albedo_shift {
            return differs(
                "albedo fraction bits",
                meta.albedo_shift.to_string(),
                first.albedo_shift.to_string(),
            );
        }
        if let Some((key, mine, theirs)) = setting_difference(&meta.settings, &first.settings) {
            return differs(key, mine.into(), theirs.into());
        }
        if meta.features != first.features {
            // The formats hash differently too; this says why they do not belong together.
            let carries = |m: &PartialMeta| {
                let has = if m.features { "with" } else { "without" };
                format!(
                    "format {} ({has} the albedo and normal buffers)",
                    m.format()
                )
            };
            return Err(error(
                path,
                format!(
                    "{}, but {} has {}: partials of one format only (render the samples of the {FORMAT_2} ones again)",
                    carries(meta),
                    first_path.display(),
                    carries(first)
                ),
            ));
        }
        if meta.hash != first.hash {
            return differs(
                "scene/settings hash",
                format!("{:016x}", meta.hash),
                format!("{:016x}", first.hash),
            );
        }
        owned.extend(meta.ranges.iter().map(|r| (r.clone(), path.as_path())));
    }
    owned.sort_by_key(|(r, _)| r.start);
    for w in owned.windows(2) {
        let ((a, pa), (b, pb)) = (&w[0], &w[1]);
        if a.end > b.start {
            return Err(error(
                pb,
                format!(
                    "samples {}..{} overlap samples {}..{} of {}",
                    b.start,
                    b.end,
                    a.start,
                    a.end,
                    pa.display()
                ),
            ));
        }
    }
    let ranges = normalize(owned.into_iter().map(|(r, _)| r).collect());
    let end = expect_end
        .unwrap_or(0)
        .max(ranges.last().map_or(0, |r| r.end));
    let missing = gaps(&ranges, end);
    let meta = PartialMeta {
        ranges,
        ..first.clone()
    };
    Ok(MergePlan { meta, missing })
}

/// Merges the partials at `paths` (checked by [`plan_merge`]) into one image's sums: the
/// colour's, and the feature buffers' if the plan's partials carry them.
pub fn merge(paths: &[PathBuf], plan: &MergePlan) -> Result<Sums, PartialError> {
    let mut sums = Sums::zero(&plan.meta);
    for path in paths {
        add_partial(path, &mut sums)?;
    }
    Ok(sums)
}
