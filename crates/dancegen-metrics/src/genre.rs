//! Genre control check: a nearest-centroid classifier on kinetic features, fit on real clips,
//! that says which genre a generated dance looks like.
//!
//! A model conditioned on genre should produce dances that a classifier fit on real clips of
//! the genres assigns to the requested genre. The real sets here are tiny (a few to a few dozen
//! clips per genre), so the classifier is deliberately simple:
//!
//! - every feature dimension is standardised by its mean and (population) standard deviation
//!   over all real clips, so that no dimension dominates because of its units (the kinetic
//!   features mix horizontal and vertical kinetic energy and energy expenditure, whose scales
//!   differ by orders of magnitude);
//! - each genre is represented by the mean (centroid) of its clips in the standardised space;
//! - a clip is assigned to the genre whose centroid is nearest (Euclidean distance).
//!
//! **Why nearest centroid:** it has no hyperparameters to tune (there is no validation set to
//! tune them on) and only `K × D` parameters estimated by means, which stay meaningful with a
//! handful of clips per genre, where a covariance (LDA/QDA), a kernel or a network would be
//! fit to noise. It is also easy to read: a genre "wins" by being closest on average.
//!
//! **How to read a share:** [`leave_one_out_accuracy`] classifies each real clip with a
//! classifier fit on the other real clips: it says how separable the genres are with these
//! features at all. The share of generated dances assigned to the requested genre is evidence of
//! genre control only in comparison with that and with chance: [`GenreClassifier::chance_uniform`]
//! (`1 / K`, a classifier guessing uniformly) and [`GenreClassifier::chance_majority`] (the
//! share of the largest genre among the real clips; nearest centroid has no class prior, but a
//! reader comparing with "always say the biggest genre" needs this number).
//!
//! Features are any fixed-length vectors (the 72 kinetic features of
//! [`crate::kinetic_features`], or their truncation to a protocol's joints, e.g. 66 under
//! LODGE's FineDance protocol); every example and every query must have the same length.

use std::collections::BTreeMap;

/// Input the classifier cannot be fit on or cannot classify.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum GenreError {
    /// Fewer than two genres among the examples: there is nothing to tell apart.
    #[error("genre classifier needs at least two genres, got {found:?}")]
    TooFewGenres { found: Vec<String> },
    /// A genre that is named but has no example (an empty or blank name, or a genre listed in
    /// [`GenreClassifier::fit_with_genres`] that no example has).
    #[error("genre {genre:?} has no example")]
    EmptyGenre { genre: String },
    /// An example's genre is not among the listed genres.
    #[error("example {index} has genre {genre:?}, which is not among the listed genres {listed:?}")]
    UnlistedGenre {
        index: usize,
        genre: String,
        listed: Vec<String>,
    },
    /// Feature vectors of different lengths.
    #[error("feature vector {index} has {got} values, expected {expected}")]
    Dimension {
        index: usize,
        got: usize,
        expected: usize,
    },
    /// A feature vector without values.
    #[error("feature vectors are empty")]
    NoFeatures,
    /// A NaN or infinite feature value.
    #[error("feature vector {index} holds a non-finite value at dimension {dim}")]
    NonFinite { index: usize, dim: usize },
}

/// Standard deviations below this (relative to `1 + |mean|`) count as zero: the dimension is
/// constant over the real clips. Its scale is then set to 1, which cannot change a decision:
/// every centroid has the same value there, so the dimension adds the same amount to every
/// distance.
const ZERO_STD_REL: f64 = 1e-12;

/// Nearest class centroid in per-dimension standardised feature space (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct GenreClassifier {
    /// Genre names, sorted; centroids and counts are in this order.
    genres: Vec<String>,
    /// Number of real examples per genre.
    counts: Vec<usize>,
    mean: Vec<f64>,
    /// Per-dimension scale (the standard deviation, or 1 for a constant dimension).
    scale: Vec<f64>,
    /// Per-genre centroid in the standardised space.
    centroids: Vec<Vec<f64>>,
}

impl GenreClassifier {
    /// Fits on `(genre, features)` examples; the genres are those the examples have.
    ///
    /// Errors: fewer than two genres, an empty genre name, feature vectors of unequal or zero
    /// length, non-finite values.
    pub fn fit<F: AsRef<[f64]>>(examples: &[(String, F)]) -> Result<Self, GenreError> {
        let mut genres: Vec<String> = examples.iter().map(|(g, _)| g.clone()).collect();
        genres.sort();
        genres.dedup();
        Self::fit_with_genres(&genres, examples)
    }

    /// Fits on `examples` with the genre list given: every listed genre must have an example and
    /// every example's genre must be listed (use this when the genres are known beforehand, e.g.
    /// from a data set manifest, so that a genre without real clips is an error, not silently
    /// dropped).
    pub fn fit_with_genres<F: AsRef<[f64]>>(
        genres: &[String],
        examples: &[(String, F)],
    ) -> Result<Self, GenreError> {
        let mut listed: Vec<String> = genres.to_vec();
        listed.sort();
        listed.dedup();
        if let Some(g) = listed.iter().find(|g| g.trim().is_empty()) {
            return Err(GenreError::EmptyGenre { genre: g.clone() });
        }
        if listed.len() < 2 {
            return Err(GenreError::TooFewGenres { found: listed });
        }
        let dims = check_features(examples)?;
        let mut counts = vec![0usize; listed.len()];
        let mut class = Vec::with_capacity(examples.len());
        for (index, (g, _)) in examples.iter().enumerate() {
            let Ok(k) = listed.binary_search(g) else {
                return Err(GenreError::UnlistedGenre {
                    index,
                    genre: g.clone(),
                    listed,
                });
            };
            counts[k] += 1;
            class.push(k);
        }
        if let Some(k) = counts.iter().position(|&c| c == 0) {
            return Err(GenreError::EmptyGenre {
                genre: listed[k].clone(),
            });
        }

        let n = examples.len() as f64;
        let mut mean = vec![0.0; dims];
        for (_, f) in examples {
            for (m, v) in mean.iter_mut().zip(f.as_ref()) {
                *m += v;
            }
        }
        mean.iter_mut().for_each(|m| *m /= n);
        let mut var = vec![0.0; dims];
        for (_, f) in examples {
            for ((s, v), m) in var.iter_mut().zip(f.as_ref()).zip(&mean) {
                *s += (v - m) * (v - m);
            }
        }
        let scale: Vec<f64> = var
            .iter()
            .zip(&mean)
            .map(|(s, m)| {
                let sd = (s / n).sqrt();
                if sd > ZERO_STD_REL * (1.0 + m.abs()) {
                    sd
                } else {
                    1.0
                }
            })
            .collect();

        let mut centroids = vec![vec![0.0; dims]; listed.len()];
        for ((_, f), &k) in examples.iter().zip(&class) {
            for (d, v) in f.as_ref().iter().enumerate() {
                centroids[k][d] += (v - mean[d]) / scale[d];
            }
        }
        for (c, &count) in centroids.iter_mut().zip(&counts) {
            c.iter_mut().for_each(|v| *v /= count as f64);
        }
        Ok(GenreClassifier {
            genres: listed,
            counts,
            mean,
            scale,
            centroids,
        })
    }

    /// The genres, sorted by name.
    pub fn genres(&self) -> &[String] {
        &self.genres
    }

    /// `(genre, number of real examples)`, sorted by genre.
    pub fn classes(&self) -> Vec<(&str, usize)> {
        self.genres
            .iter()
            .map(String::as_str)
            .zip(self.counts.iter().copied())
            .collect()
    }

    /// Feature length the classifier was fit on.
    pub fn dims(&self) -> usize {
        self.mean.len()
    }

    /// `1 / K`: the expected accuracy of a uniform guess among the `K` genres.
    pub fn chance_uniform(&self) -> f64 {
        1.0 / self.genres.len() as f64
    }

    /// Share of the largest genre among the real examples: the accuracy of always answering
    /// that genre on data distributed like the real set.
    pub fn chance_majority(&self) -> f64 {
        let total: usize = self.counts.iter().sum();
        *self.counts.iter().max().unwrap_or(&0) as f64 / total as f64
    }

    /// Euclidean distance of `features` to each genre's centroid in the standardised space,
    /// in [`Self::genres`] order (smaller = more like that genre).
    pub fn scores(&self, features: &[f64]) -> Result<Vec<f64>, GenreError> {
        if features.len() != self.dims() {
            return Err(GenreError::Dimension {
                index: 0,
                got: features.len(),
                expected: self.dims(),
            });
        }
        if let Some(dim) = features.iter().position(|v| !v.is_finite()) {
            return Err(GenreError::NonFinite { index: 0, dim });
        }
        let z: Vec<f64> = features
            .iter()
            .zip(self.mean.iter().zip(&self.scale))
            .map(|(v, (m, s))| (v - m) / s)
            .collect();
        Ok(self
            .centroids
            .iter()
            .map(|c| {
                c.iter()
                    .zip(&z)
                    .map(|(a, b)| (a - b) * (a - b))
                    .sum::<f64>()
                    .sqrt()
            })
            .collect())
    }

    /// The genre whose centroid is nearest (ties: the first genre by name). Errors for a feature
    /// vector of the wrong length or with non-finite values.
    pub fn predict(&self, features: &[f64]) -> Result<&str, GenreError> {
        let d = self.scores(features)?;
        let mut best = 0;
        for (k, v) in d.iter().enumerate() {
            if *v < d[best] {
                best = k;
            }
        }
        Ok(self.genres[best].as_str())
    }
}

/// Result of [`leave_one_out_accuracy`].
#[derive(Clone, Debug, PartialEq)]
pub struct LeaveOneOut {
    /// Examples classified as their own genre.
    pub correct: usize,
    pub total: usize,
    /// The genre each example was assigned, in input order.
    pub predicted: Vec<String>,
}

impl LeaveOneOut {
    /// `correct / total`.
    pub fn accuracy(&self) -> f64 {
        self.correct as f64 / self.total as f64
    }
}

/// Classifies each example with a classifier fit (standardisation included) on all the others.
///
/// An example that is the only one of its genre cannot be classified right (the classifier fit
/// without it does not know its genre) and counts as wrong; so does one whose removal leaves a
/// single genre (it is assigned that genre). This is what the classifier would do with a new
/// clip of an unseen genre, and keeps the accuracy honest on tiny sets.
///
/// Errors as [`GenreClassifier::fit`] on the whole set.
pub fn leave_one_out_accuracy<F: AsRef<[f64]>>(
    examples: &[(String, F)],
) -> Result<LeaveOneOut, GenreError> {
    // Validates the whole set (genres, dimensions, finiteness) once.
    GenreClassifier::fit(examples)?;
    let mut predicted = Vec::with_capacity(examples.len());
    let mut correct = 0;
    for (i, (genre, f)) in examples.iter().enumerate() {
        let rest: Vec<(String, &[f64])> = examples
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != i)
            .map(|(_, (g, f))| (g.clone(), f.as_ref()))
            .collect();
        let mut left: Vec<&str> = rest.iter().map(|(g, _)| g.as_str()).collect();
        left.sort_unstable();
        left.dedup();
        let p = if left.len() < 2 {
            left[0].to_string()
        } else {
            GenreClassifier::fit(&rest)?
                .predict(f.as_ref())?
                .to_string()
        };
        if p == *genre {
            correct += 1;
        }
        predicted.push(p);
    }
    Ok(LeaveOneOut {
        correct,
        total: examples.len(),
        predicted,
    })
}

/// Splits `examples` into those whose genre has at least `min` examples and the genres left out
/// (genre → its number of examples). The order of the kept examples is unchanged.
///
/// Why: a genre with one clip has that one take's features as its "centroid", and leave-one-out
/// cannot test it (the fit without it does not know the genre), so the class stands for one
/// performance, not a genre; with `min = 2` such classes stop attracting every dance that
/// happens to resemble that take (issue 16: solo-v3's single street-jazz take).
pub fn keep_genres_with_at_least<F>(
    examples: Vec<(String, F)>,
    min: usize,
) -> (Vec<(String, F)>, BTreeMap<String, usize>) {
    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    for (g, _) in &examples {
        *counts.entry(g.clone()).or_insert(0) += 1;
    }
    counts.retain(|_, n| *n < min);
    let kept = examples
        .into_iter()
        .filter(|(g, _)| !counts.contains_key(g))
        .collect();
    (kept, counts)
}

/// Number of clips assigned to each genre, for a report (genres with no clip are left out).
pub fn count_predictions<'a>(
    predicted: impl IntoIterator<Item = &'a str>,
) -> BTreeMap<String, usize> {
    let mut out = BTreeMap::new();
    for p in predicted {
        *out.entry(p.to_string()).or_insert(0) += 1;
    }
    out
}

/// Common feature length of the examples, checking lengths and finiteness.
fn check_features<F: AsRef<[f64]>>(examples: &[(String, F)]) -> Result<usize, GenreError> {
    let dims = examples.first().map_or(0, |(_, f)| f.as_ref().len());
    if dims == 0 {
        return Err(GenreError::NoFeatures);
    }
    for (index, (_, f)) in examples.iter().enumerate() {
        let f = f.as_ref();
        if f.len() != dims {
            return Err(GenreError::Dimension {
                index,
                got: f.len(),
                expected: dims,
            });
        }
        if let Some(dim) = f.iter().position(|v| !v.is_finite()) {
            return Err(GenreError::NonFinite { index, dim });
        }
    }
    Ok(dims)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic pseudo-random numbers in [-1, 1) (a small LCG; no dependency).
    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        }
    }

    /// `n` examples per genre around well separated centres in 72 dimensions. Dimension 0 has a
    /// scale of 1000 and carries no genre information (pure noise): without standardisation it
    /// would swamp the informative dimensions.
    fn clusters(n: usize, rng: &mut Lcg) -> Vec<(String, [f64; 72])> {
        let mut out = Vec::new();
        for (g, centre) in [("break", 0.0), ("modern", 5.0), ("salsa", 10.0)] {
            for _ in 0..n {
                let mut f = [0.0; 72];
                f[0] = 1000.0 * rng.next();
                for (d, v) in f.iter_mut().enumerate().skip(1) {
                    // Dimensions 1..=40 tell the genres apart, 41..=70 are noise.
                    let c = if d <= 40 { centre } else { 0.0 };
                    *v = c + rng.next();
                }
                // A constant dimension (zero std) must not break the fit.
                f[71] = 3.0;
                out.push((g.to_string(), f));
            }
        }
        out
    }

    #[test]
    fn genres_with_too_few_examples_are_left_out() {
        let ex = vec![
            ("salsa".to_string(), vec![1.0]),
            ("jazz".to_string(), vec![2.0]),
            ("modern".to_string(), vec![3.0]),
            ("salsa".to_string(), vec![4.0]),
            ("modern".to_string(), vec![5.0]),
        ];
        let (kept, left) = keep_genres_with_at_least(ex.clone(), 2);
        let names: Vec<&str> = kept.iter().map(|(g, _)| g.as_str()).collect();
        assert_eq!(names, ["salsa", "modern", "salsa", "modern"]);
        assert_eq!(kept[1].1, vec![3.0]);
        assert_eq!(left, BTreeMap::from([("jazz".to_string(), 1)]));
        let (kept, left) = keep_genres_with_at_least(ex.clone(), 1);
        assert_eq!((kept.len(), left.len()), (5, 0));
        let (kept, left) = keep_genres_with_at_least(ex, 3);
        assert!(kept.is_empty());
        assert_eq!(left.len(), 3);
    }
    #[test]
    fn separable_clusters_are_classified_right() {
        let mut rng = Lcg(7);
        let train = clusters(5, &mut rng);
        let clf = GenreClassifier::fit(&train).unwrap();
        assert_eq!(clf.genres(), ["break", "modern", "salsa"]);
        assert_eq!(clf.classes(), [("break", 5), ("modern", 5), ("salsa", 5)]);
        assert_eq!(clf.dims(), 72);
        let test = clusters(20, &mut rng);
        for (g, f) in &test {
            assert_eq!(clf.predict(f).unwrap(), g);
            let s = clf.scores(f).unwrap();
            let k = clf.genres().iter().position(|x| x == g).unwrap();
            assert!(s.iter().enumerate().all(|(j, v)| j == k || *v > s[k]));
        }
        // The constant dimension got scale 1, so the scores stay finite.
        assert!(clf.scale[71] == 1.0 && clf.scale.iter().all(|s| s.is_finite()));
    }

    #[test]
    fn unstandardised_noise_dimension_is_neutralised() {
        // Shift a salsa example's noise dimension far away: standardisation keeps it salsa.
        let mut rng = Lcg(11);
        let train = clusters(6, &mut rng);
        let clf = GenreClassifier::fit(&train).unwrap();
        let mut f = train.last().unwrap().1;
        f[0] = -1000.0;
        assert_eq!(clf.predict(&f).unwrap(), "salsa");
    }

    #[test]
    fn chance_levels() {
        let ex = vec![
            ("a".to_string(), vec![0.0, 0.0]),
            ("a".to_string(), vec![0.1, 0.0]),
            ("a".to_string(), vec![0.0, 0.1]),
            ("b".to_string(), vec![5.0, 5.0]),
        ];
        let clf = GenreClassifier::fit(&ex).unwrap();
        assert_eq!(clf.chance_uniform(), 0.5);
        assert_eq!(clf.chance_majority(), 0.75);
        assert_eq!(clf.predict(&[4.0, 4.0]).unwrap(), "b");
        assert_eq!(clf.predict(&[0.5, 0.5]).unwrap(), "a");
    }

    #[test]
    fn leave_one_out_on_clusters() {
        let mut rng = Lcg(3);
        let ex = clusters(4, &mut rng);
        let loo = leave_one_out_accuracy(&ex).unwrap();
        assert_eq!((loo.correct, loo.total), (12, 12));
        assert_eq!(loo.accuracy(), 1.0);
        let want: Vec<&str> = ex.iter().map(|(g, _)| g.as_str()).collect();
        assert_eq!(loo.predicted, want);
    }

    #[test]
    fn leave_one_out_counts_singletons_and_overlap_as_wrong() {
        // Genre c has a single example: it cannot be right when left out.
        let mut ex = vec![
            ("a".to_string(), vec![0.0]),
            ("a".to_string(), vec![0.2]),
            ("b".to_string(), vec![10.0]),
            ("b".to_string(), vec![10.2]),
            ("c".to_string(), vec![20.0]),
        ];
        let loo = leave_one_out_accuracy(&ex).unwrap();
        assert_eq!((loo.correct, loo.total), (4, 5));
        assert_eq!(loo.predicted[4], "b");
        // Two genres drawn from one distribution: about chance, certainly not perfect.
        let mut rng = Lcg(5);
        ex = (0..40)
            .map(|i| {
                let g = if i % 2 == 0 { "a" } else { "b" };
                (g.to_string(), vec![rng.next(), rng.next()])
            })
            .collect();
        let acc = leave_one_out_accuracy(&ex).unwrap().accuracy();
        assert!(acc < 0.8, "indistinguishable genres got LOO accuracy {acc}");
        // Two genres of one example each: neither can be classified right.
        let two = vec![("a".to_string(), vec![0.0]), ("b".to_string(), vec![1.0])];
        let loo = leave_one_out_accuracy(&two).unwrap();
        assert_eq!(loo.correct, 0);
        assert_eq!(loo.predicted, ["b", "a"]);
    }

    #[test]
    fn errors() {
        let one: Vec<(String, Vec<f64>)> = vec![("a".into(), vec![1.0]), ("a".into(), vec![2.0])];
        assert_eq!(
            GenreClassifier::fit(&one).unwrap_err(),
            GenreError::TooFewGenres {
                found: vec!["a".into()]
            }
        );
        let none: Vec<(String, Vec<f64>)> = Vec::new();
        assert!(matches!(
            GenreClassifier::fit(&none),
            Err(GenreError::TooFewGenres { .. })
        ));
        assert!(matches!(
            leave_one_out_accuracy(&one),
            Err(GenreError::TooFewGenres { .. })
        ));
        let blank: Vec<(String, Vec<f64>)> = vec![("a".into(), vec![1.0]), (" ".into(), vec![2.0])];
        assert!(matches!(
            GenreClassifier::fit(&blank),
            Err(GenreError::EmptyGenre { .. })
        ));
        let ab: Vec<(String, Vec<f64>)> = vec![("a".into(), vec![1.0]), ("b".into(), vec![2.0])];
        let listed = ["a".to_string(), "b".to_string(), "c".to_string()];
        assert_eq!(
            GenreClassifier::fit_with_genres(&listed, &ab).unwrap_err(),
            GenreError::EmptyGenre { genre: "c".into() }
        );
        assert!(matches!(
            GenreClassifier::fit_with_genres(&listed[..1], &ab),
            Err(GenreError::TooFewGenres { .. })
        ));
        let listed_ac = ["a".to_string(), "c".to_string()];
        assert!(matches!(
            GenreClassifier::fit_with_genres(&listed_ac, &ab),
            Err(GenreError::UnlistedGenre { index: 1, .. })
        ));
        let ragged: Vec<(String, Vec<f64>)> =
            vec![("a".into(), vec![1.0, 0.0]), ("b".into(), vec![2.0])];
        assert_eq!(
            GenreClassifier::fit(&ragged).unwrap_err(),
            GenreError::Dimension {
                index: 1,
                got: 1,
                expected: 2
            }
        );
        let empty: Vec<(String, Vec<f64>)> = vec![("a".into(), vec![]), ("b".into(), vec![])];
        assert_eq!(
            GenreClassifier::fit(&empty).unwrap_err(),
            GenreError::NoFeatures
        );
        let nan: Vec<(String, Vec<f64>)> =
            vec![("a".into(), vec![1.0]), ("b".into(), vec![f64::NAN])];
        assert_eq!(
            GenreClassifier::fit(&nan).unwrap_err(),
            GenreError::NonFinite { index: 1, dim: 0 }
        );
        let clf = GenreClassifier::fit(&ab).unwrap();
        assert!(matches!(
            clf.predict(&[1.0, 2.0]),
            Err(GenreError::Dimension { got: 2, .. })
        ));
        assert!(matches!(
            clf.predict(&[f64::INFINITY]),
            Err(GenreError::NonFinite { .. })
        ));
    }

    #[test]
    fn counts() {
        let c = count_predictions(["salsa", "break", "salsa"]);
        assert_eq!(c.get("salsa"), Some(&2));
        assert_eq!(c.get("break"), Some(&1));
        assert_eq!(c.len(), 2);
    }
}
