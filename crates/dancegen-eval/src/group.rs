//! Group metrics of scenes (`N ≥ 2` dancers): GMR over the set, GMC and TIF per scene, on the
//! dancers' world positions (GCD works on the scene as placed; its frame time is fixed at 1/30).

use anyhow::{Context, Result};
use dancegen_metrics::group::{
    CapsuleRadii, collision_share, gmc, group_kinetic_features, min_root_distance, tif,
};

use super::input::Clip;

/// Group kinetic features (float32, as GCD stacks them) of the group scenes of a set.
pub fn gmr_features(set: &[Clip]) -> Result<Vec<Vec<f64>>> {
    set.iter()
        .filter(|c| c.is_group())
        .map(|c| {
            let f = group_kinetic_features(&c.placed_refs())
                .with_context(|| format!("{}", c.path.display()))?;
            Ok(f.iter().map(|&v| v as f32 as f64).collect())
        })
        .collect()
}

/// GMC or TIF of one clip; `None` for a solo clip.
pub fn clip_metric(m: &str, c: &Clip) -> Result<Option<f64>> {
    if !c.is_group() {
        return Ok(None);
    }
    let dancers = c.placed_refs();
    let v = match m {
        "gmc" => gmc(&dancers),
        "tif" => tif(&dancers, &CapsuleRadii::default()),
        "collision" => collision_share(&dancers, &CapsuleRadii::default()),
        "min_distance" => min_root_distance(&dancers),
        other => unreachable!("group metric {other}"),
    };
    v.with_context(|| format!("{}: {m}", c.path.display()))
}
