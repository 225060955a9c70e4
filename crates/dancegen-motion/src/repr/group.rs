//! Per-dancer stacks for group models (TCDiff, `Da1yuqin/TCDiff:dataset/group_dataset.py`;
//! anchors.md C.5).
//!
//! Layout: `(N, T, 151)` row-major — dancer-major, each dancer's `(T, 151)` block is exactly
//! [`Edge151`] (EDGE's Z-up conversion and velocity contacts applied per dancer, independently).
//! All dancers share the frame count and 30 fps. AIOZ-GDance `root_trans` is used as the pelvis
//! position as stored (metres, Y-up, 30 fps; C.5).

use super::{Edge151, ReprError, SmplMotion, frames_of};

/// A group of dancers with equal frame counts and frame rates.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupMotion {
    pub dancers: Vec<SmplMotion>,
}

impl GroupMotion {
    /// Common frame count (0 for an empty group).
    pub fn frames(&self) -> usize {
        self.dancers.first().map_or(0, SmplMotion::frames)
    }
}

/// TCDiff's per-dancer EDGE stack; see the module documentation.
#[derive(Debug, Clone, Copy, Default)]
pub struct GroupEdge151;

impl GroupEdge151 {
    /// Encodes to `(N, T, 151)`; all dancers must have the same frame count.
    pub fn encode(g: &GroupMotion) -> Result<Vec<f32>, ReprError> {
        let t = g.frames();
        let mut out = Vec::with_capacity(g.dancers.len() * t * Edge151::DIMS);
        for (i, d) in g.dancers.iter().enumerate() {
            if d.frames() != t {
                return Err(ReprError::Invalid(format!(
                    "dancer {i} has {} frames, dancer 0 has {t}",
                    d.frames()
                )));
            }
            out.extend(Edge151::encode(d)?);
        }
        Ok(out)
    }

    /// Decodes `(N, T, 151)` with `dancers = N`.
    pub fn decode(data: &[f32], dancers: usize) -> Result<GroupMotion, ReprError> {
        if dancers == 0 {
            return Ok(GroupMotion {
                dancers: Vec::new(),
            });
        }
        let rows = frames_of("GroupEdge151::decode", data, Edge151::DIMS)?;
        if rows % dancers != 0 {
            return Err(ReprError::Invalid(format!(
                "{rows} frames do not split into {dancers} dancers"
            )));
        }
        let block = rows / dancers * Edge151::DIMS;
        let dancers = data
            .chunks_exact(block.max(1))
            .map(Edge151::decode)
            .collect::<Result<_, _>>()?;
        Ok(GroupMotion { dancers })
    }
}
