//! Duet metrics (Duolando): which leader goes with which follower, then FID_cd / Div_cd over the
//! set and BED per pair, on world positions (the cross-distance feature is absolute).

use std::collections::BTreeMap;

use anyhow::{Context, Result, bail};
use dancegen_metrics::duet::{
    beat_echo_degree, contact_range_share, cross_distance_feature, interpenetration_rate,
};

use super::input::Clip;

/// A follower with its leader (world positions, cut to the protocol's length).
pub struct Pair<'a> {
    pub follower: &'a [f64],
    pub leader: &'a [f64],
}

/// The duet of each clip, or `None` for a clip that is not one. With leader clips (`--leader`,
/// `--gt-leader`), each follower clip takes the leader of the same file stem; without, a clip of
/// exactly two dancers is `[leader, follower]`.
pub fn pairs<'a>(
    followers: &'a [Clip],
    leaders: &'a [Clip],
    flag: &str,
) -> Result<Vec<Option<Pair<'a>>>> {
    if leaders.is_empty() {
        return Ok(followers
            .iter()
            .map(|c| {
                (c.placed.len() == 2).then(|| Pair {
                    follower: &c.placed[1],
                    leader: &c.placed[0],
                })
            })
            .collect());
    }
    let by_stem: BTreeMap<String, &Clip> = leaders.iter().map(|c| (c.stem(), c)).collect();
    if let Some(l) = leaders.iter().find(|l| l.is_group()) {
        bail!(
            "{}: a {flag} clip must hold one dancer, it holds {}",
            l.path.display(),
            l.dancers.len()
        );
    }
    let mut out = Vec::with_capacity(followers.len());
    for c in followers {
        if c.is_group() {
            bail!(
                "{}: holds {} dancers; with {flag} each follower clip must hold one",
                c.path.display(),
                c.dancers.len()
            );
        }
        let Some(l) = by_stem.get(&c.stem()) else {
            bail!(
                "{}: no {flag} clip with the file stem {:?}",
                c.path.display(),
                c.stem()
            );
        };
        out.push(Some(Pair {
            follower: &c.placed[0],
            leader: &l.placed[0],
        }));
    }
    let used: Vec<String> = followers.iter().map(Clip::stem).collect();
    for l in leaders.iter().filter(|l| !used.contains(&l.stem())) {
        tracing::warn!(
            "{}: {flag} clip without a follower; ignored",
            l.path.display()
        );
    }
    Ok(out)
}

/// Cross-distance features of the duets of a set.
pub fn features(clips: &[Clip], pairs: &[Option<Pair>]) -> Result<Vec<Vec<f64>>> {
    clips
        .iter()
        .zip(pairs)
        .filter_map(|(c, p)| p.as_ref().map(|p| (c, p)))
        .map(|(c, p)| {
            cross_distance_feature(p.follower, p.leader)
                .with_context(|| format!("{}", c.path.display()))
        })
        .collect()
}

/// A per-duet metric: `bed` (Beat Echo Degree), `ipr`, `contact_range`.
pub fn clip_metric(m: &str, c: &Clip, p: &Pair) -> Result<Option<f64>> {
    match m {
        "bed" => beat_echo_degree(p.follower, p.leader),
        "ipr" => interpenetration_rate(p.follower, p.leader),
        "contact_range" => contact_range_share(p.follower, p.leader),
        other => unreachable!("{other} is not a per-duet metric"),
    }
    .with_context(|| format!("{}: {m}", c.path.display()))
}
