//! ARKit's 52 face blendshapes.
//!
//! The order is the column order of the CSV that Epic's Live Link Face app exports (the
//! de-facto interchange order: UE's importer, Blender and Maya add-ons read it). It groups the
//! left eye, the right eye, jaw and mouth, brows, cheeks, nose and tongue. Note that it has
//! `jawRight` before `jawLeft` and `mouthRight` before `mouthLeft`, unlike Apple's alphabetical
//! documentation list. Readers match columns by name, so only our own files depend on it.

/// Blendshapes per frame.
pub const ARKIT_COUNT: usize = 52;

/// The 52 names, camelCase as ARKit spells them (`ARFaceAnchor.BlendShapeLocation`).
pub const ARKIT_NAMES: [&str; ARKIT_COUNT] = [
    "eyeBlinkLeft",
    "eyeLookDownLeft",
    "eyeLookInLeft",
    "eyeLookOutLeft",
    "eyeLookUpLeft",
    "eyeSquintLeft",
    "eyeWideLeft",
    "eyeBlinkRight",
    "eyeLookDownRight",
    "eyeLookInRight",
    "eyeLookOutRight",
    "eyeLookUpRight",
    "eyeSquintRight",
    "eyeWideRight",
    "jawForward",
    "jawRight",
    "jawLeft",
    "jawOpen",
    "mouthClose",
    "mouthFunnel",
    "mouthPucker",
    "mouthRight",
    "mouthLeft",
    "mouthSmileLeft",
    "mouthSmileRight",
    "mouthFrownLeft",
    "mouthFrownRight",
    "mouthDimpleLeft",
    "mouthDimpleRight",
    "mouthStretchLeft",
    "mouthStretchRight",
    "mouthRollLower",
    "mouthRollUpper",
    "mouthShrugLower",
    "mouthShrugUpper",
    "mouthPressLeft",
    "mouthPressRight",
    "mouthLowerDownLeft",
    "mouthLowerDownRight",
    "mouthUpperUpLeft",
    "mouthUpperUpRight",
    "browDownLeft",
    "browDownRight",
    "browInnerUp",
    "browOuterUpLeft",
    "browOuterUpRight",
    "cheekPuff",
    "cheekSquintLeft",
    "cheekSquintRight",
    "noseSneerLeft",
    "noseSneerRight",
    "tongueOut",
];

/// Index of an ARKit name, ignoring the case of the first letter (`EyeBlinkLeft` and
/// `eyeBlinkLeft` both match), so Live Link's PascalCase columns resolve too.
pub fn arkit_index(name: &str) -> Option<usize> {
    // Byte slicing is safe here: every ARKit name is ASCII, and a name whose first byte is not
    // ASCII cannot match (compared as bytes, never sliced at a char boundary).
    let b = name.as_bytes();
    ARKIT_NAMES.iter().position(|n| {
        let nb = n.as_bytes();
        nb.len() == b.len() && nb[0].eq_ignore_ascii_case(&b[0]) && nb[1..] == b[1..]
    })
}

/// Live Link's PascalCase spelling of `ARKIT_NAMES[i]`.
pub fn pascal_case(i: usize) -> String {
    let n = ARKIT_NAMES[i];
    n[..1].to_ascii_uppercase() + &n[1..]
}

/// A face track or face file that cannot be used, with what is wrong.
#[derive(Debug, thiserror::Error)]
pub enum FaceError {
    #[error("face weights: {0}")]
    Shape(String),
    #[error("{path}: {reason}")]
    File { path: String, reason: String },
}

/// `(T, 52)` ARKit weights at `fps`, every value in [0, 1].
#[derive(Debug, Clone, PartialEq)]
pub struct FaceWeights {
    pub fps: f32,
    weights: Vec<f32>,
}

impl FaceWeights {
    /// Checks the shape (a multiple of 52), the frame rate and the range (finite, in [0, 1]; the
    /// first bad value is named by frame and blendshape).
    pub fn new(weights: Vec<f32>, fps: f32) -> Result<Self, FaceError> {
        if !weights.len().is_multiple_of(ARKIT_COUNT) {
            return Err(FaceError::Shape(format!(
                "{} values is not a whole number of {ARKIT_COUNT}-weight frames",
                weights.len()
            )));
        }
        if !(fps.is_finite() && fps > 0.0) {
            return Err(FaceError::Shape(format!(
                "frame rate {fps} is not positive"
            )));
        }
        if let Some(i) = weights
            .iter()
            .position(|w| !(w.is_finite() && (0.0..=1.0).contains(w)))
        {
            return Err(FaceError::Shape(format!(
                "frame {} {} = {} is outside [0, 1]",
                i / ARKIT_COUNT,
                ARKIT_NAMES[i % ARKIT_COUNT],
                weights[i]
            )));
        }
        Ok(FaceWeights { fps, weights })
    }

    /// Number of frames.
    pub fn frames(&self) -> usize {
        self.weights.len() / ARKIT_COUNT
    }

    /// Frame `f`'s 52 weights.
    pub fn frame(&self, f: usize) -> &[f32] {
        &self.weights[f * ARKIT_COUNT..(f + 1) * ARKIT_COUNT]
    }

    /// All weights, frame-major.
    pub fn as_slice(&self) -> &[f32] {
        &self.weights
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_camel_case_and_resolve_both_ways() {
        let mut seen = std::collections::BTreeSet::new();
        for (i, n) in ARKIT_NAMES.iter().enumerate() {
            assert!(seen.insert(*n), "{n} twice");
            assert!(n.chars().next().unwrap().is_ascii_lowercase(), "{n}");
            assert_eq!(arkit_index(n), Some(i));
            assert_eq!(arkit_index(&pascal_case(i)), Some(i));
        }
        // 7 + 7 eye shapes; 20 left/right pairs in all, each side's name the other's with the
        // side swapped; 12 unpaired.
        assert_eq!(
            ARKIT_NAMES.iter().filter(|n| n.starts_with("eye")).count(),
            14
        );
        let left: Vec<&&str> = ARKIT_NAMES.iter().filter(|n| n.ends_with("Left")).collect();
        assert_eq!(left.len(), 20);
        for n in left {
            let right = format!("{}Right", n.strip_suffix("Left").unwrap());
            assert!(arkit_index(&right).is_some(), "{right}");
        }
        assert_eq!(
            ARKIT_NAMES.iter().filter(|n| n.ends_with("Right")).count(),
            20
        );
        assert_eq!(arkit_index("JawOpen"), Some(17));
        assert_eq!(arkit_index("jawopen"), None);
        assert_eq!(arkit_index("HeadYaw"), None);
        // Bad input from a CSV header: no panic on multi-byte text or an empty name.
        assert_eq!(arkit_index("ñwOpen"), None); // 7 bytes, as "jawOpen"
        assert_eq!(arkit_index("éyeBlinkLeft"), None);
        assert_eq!(arkit_index(""), None);
    }

    #[test]
    fn weights_check_shape_rate_and_range() {
        let ok = FaceWeights::new(vec![0.5; 104], 30.0).unwrap();
        assert_eq!(ok.frames(), 2);
        assert_eq!(ok.frame(1).len(), 52);
        let e = FaceWeights::new(vec![0.5; 53], 30.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("53 values"), "{e}");
        let mut w = vec![0.0; 104];
        w[52 + 17] = 1.5;
        let e = FaceWeights::new(w, 30.0).unwrap_err().to_string();
        assert!(e.contains("frame 1 jawOpen = 1.5"), "{e}");
        assert!(FaceWeights::new(vec![f32::NAN; 52], 30.0).is_err());
        assert!(FaceWeights::new(vec![0.0; 52], 0.0).is_err());
    }
}
