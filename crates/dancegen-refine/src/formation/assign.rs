//! Which dancer takes which slot of the next formation: the assignment with the least total
//! squared travel (group.md §4.4, "morph between templates with Hungarian assignment").
//!
//! Squared distance rather than distance: it spreads the walking over the group instead of
//! letting one dancer cross the stage so the others can stand still, and dancers moving on
//! the straight, equally timed paths of a squared-optimal assignment are never at one point at
//! one time (optimality gives `(a₁ − a₂)·(b₁ − b₂) ≥ 0`, which a meeting would violate). That
//! is not yet [`super::MIN_SEPARATION_M`]: [`super::transition`] checks it.
//! Solved exactly by the Hungarian method (Kuhn 1955, Munkres 1957) with potentials, O(n²m);
//! trivial for n ≤ 5 but general.

use super::StagePos;

/// Why no assignment was found.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AssignError {
    #[error("cost matrix row {row} has {found} columns, row 0 has {expected}")]
    Ragged {
        row: usize,
        found: usize,
        expected: usize,
    },
    #[error("{rows} dancers but only {cols} slots")]
    TooFewSlots { rows: usize, cols: usize },
    #[error("cost[{row}][{col}] = {value} is not a finite number")]
    NotFinite { row: usize, col: usize, value: f64 },
}

/// The assignment of rows (dancers) to distinct columns (slots) with the least total cost:
/// `result[row] = column`. Needs at least as many columns as rows and finite costs. Among equal
/// optima the result is deterministic (it depends only on the matrix).
pub fn hungarian(cost: &[Vec<f64>]) -> Result<Vec<usize>, AssignError> {
    let n = cost.len();
    if n == 0 {
        return Ok(Vec::new());
    }
    let m = cost[0].len();
    let mut scale: f64 = 0.0;
    for (row, r) in cost.iter().enumerate() {
        if r.len() != m {
            return Err(AssignError::Ragged {
                row,
                found: r.len(),
                expected: m,
            });
        }
        for (col, &value) in r.iter().enumerate() {
            if !value.is_finite() {
                return Err(AssignError::NotFinite { row, col, value });
            }
            scale = scale.max(value.abs());
        }
    }
    if n > m {
        return Err(AssignError::TooFewSlots { rows: n, cols: m });
    }
    // Dividing by the largest |cost| keeps the potentials near 1, so no sum of finite costs
    // can overflow to infinity; a positive scale does not change the optimum.
    let scale = if scale > 0.0 { scale } else { 1.0 };
    let a = |i: usize, j: usize| cost[i - 1][j - 1] / scale;

    // 1-based potentials u (rows), v (columns); p[j] = row matched to column j (0 = none);
    // way[j] = previous column on the augmenting path. Column 0 is the virtual start.
    let (mut u, mut v) = (vec![0.0; n + 1], vec![0.0; m + 1]);
    let (mut p, mut way) = (vec![0usize; m + 1], vec![0usize; m + 1]);
    for i in 1..=n {
        p[0] = i;
        let mut j0 = 0;
        let mut min_v = vec![f64::INFINITY; m + 1];
        let mut used = vec![false; m + 1];
        loop {
            used[j0] = true;
            let i0 = p[j0];
            let (mut delta, mut j1) = (f64::INFINITY, 0);
            for j in 1..=m {
                if used[j] {
                    continue;
                }
                let reduced = a(i0, j) - u[i0] - v[j];
                if reduced < min_v[j] {
                    min_v[j] = reduced;
                    way[j] = j0;
                }
                if min_v[j] < delta {
                    delta = min_v[j];
                    j1 = j;
                }
            }
            // n ≤ m leaves an unused column and scaled costs keep every reduced cost finite,
            // so a column is always found; stopping here instead of looping is only defence.
            if j1 == 0 {
                break;
            }
            for j in 0..=m {
                if used[j] {
                    u[p[j]] += delta;
                    v[j] -= delta;
                } else {
                    min_v[j] -= delta;
                }
            }
            j0 = j1;
            if p[j0] == 0 {
                break;
            }
        }
        while j0 != 0 {
            let j1 = way[j0];
            p[j0] = p[j1];
            j0 = j1;
        }
    }
    let mut result = vec![0; n];
    for j in 1..=m {
        if p[j] != 0 {
            result[p[j] - 1] = j - 1;
        }
    }
    Ok(result)
}

/// The slot of `slots` each dancer at `from` takes (`result[dancer] = slot`), minimising the
/// total squared travel.
pub fn assign_slots(from: &[StagePos], slots: &[StagePos]) -> Result<Vec<usize>, AssignError> {
    let cost: Vec<Vec<f64>> = from
        .iter()
        .map(|p| {
            slots
                .iter()
                .map(|q| (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2))
                .collect()
        })
        .collect();
    hungarian(&cost)
}

/// Each dancer's target under an assignment: `targets[d] = slots[assignment[d]]`.
pub fn targets(slots: &[StagePos], assignment: &[usize]) -> Vec<StagePos> {
    assignment.iter().map(|&s| slots[s]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 64-bit LCG (Knuth's MMIX constants), top bits as a uniform in [0, 1).
    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    fn brute_force(cost: &[Vec<f64>]) -> f64 {
        fn go(cost: &[Vec<f64>], row: usize, used: &mut Vec<bool>) -> f64 {
            if row == cost.len() {
                return 0.0;
            }
            let mut best = f64::INFINITY;
            for col in 0..used.len() {
                if !used[col] {
                    used[col] = true;
                    best = best.min(cost[row][col] + go(cost, row + 1, used));
                    used[col] = false;
                }
            }
            best
        }
        go(cost, 0, &mut vec![false; cost[0].len()])
    }

    fn total(cost: &[Vec<f64>], assignment: &[usize]) -> f64 {
        assignment
            .iter()
            .enumerate()
            .map(|(r, &c)| cost[r][c])
            .sum()
    }

    fn is_injective(assignment: &[usize], cols: usize) -> bool {
        let mut seen = vec![false; cols];
        assignment
            .iter()
            .all(|&c| c < cols && !std::mem::replace(&mut seen[c], true))
    }

    #[test]
    fn matches_brute_force_on_random_instances() {
        let mut rng = Lcg(17);
        for trial in 0..600 {
            let n = 1 + trial % 6;
            let m = n + (trial / 6) % 3;
            // Integer costs make ties common; real ones (squared travel) are the real case.
            let cost: Vec<Vec<f64>> = (0..n)
                .map(|_| {
                    (0..m)
                        .map(|_| {
                            let x = rng.next() * 10.0;
                            if trial % 2 == 0 {
                                x.floor()
                            } else {
                                x * x - 3.0
                            }
                        })
                        .collect()
                })
                .collect();
            let assignment = hungarian(&cost).unwrap();
            assert!(is_injective(&assignment, m), "{assignment:?}");
            let (got, best) = (total(&cost, &assignment), brute_force(&cost));
            assert!(
                (got - best).abs() <= 1e-9 * best.abs().max(1.0),
                "trial {trial}: {got} vs {best}"
            );
        }
    }

    #[test]
    fn dancers_take_the_nearest_slots() {
        let from = [[-1.0, 0.0], [0.0, 0.0], [1.0, 0.0]];
        let slots = [[1.1, 0.5], [-1.1, 0.5], [0.0, 0.5]];
        let assignment = assign_slots(&from, &slots).unwrap();
        assert_eq!(assignment, vec![1, 2, 0]);
        assert_eq!(
            targets(&slots, &assignment),
            vec![[-1.1, 0.5], [0.0, 0.5], [1.1, 0.5]]
        );
        assert_eq!(assign_slots(&[], &[]).unwrap(), Vec::<usize>::new());
    }

    #[test]
    fn bad_matrices_are_errors_not_panics() {
        let ragged = vec![vec![1.0, 2.0], vec![1.0]];
        assert!(matches!(
            hungarian(&ragged),
            Err(AssignError::Ragged { row: 1, .. })
        ));
        let tall = vec![vec![1.0], vec![2.0]];
        assert!(matches!(
            hungarian(&tall),
            Err(AssignError::TooFewSlots { rows: 2, cols: 1 })
        ));
        let nan = vec![vec![1.0, f64::NAN]];
        assert!(matches!(
            hungarian(&nan),
            Err(AssignError::NotFinite { row: 0, col: 1, .. })
        ));
        // Huge finite costs neither overflow nor hang.
        let huge = vec![vec![f64::MAX, -f64::MAX], vec![-f64::MAX, f64::MAX]];
        assert_eq!(hungarian(&huge).unwrap(), vec![1, 0]);
    }
}
