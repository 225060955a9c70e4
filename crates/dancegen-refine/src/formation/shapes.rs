//! Formation templates (group.md §4.3): where `n` dancers stand for each named shape.
//!
//! `spacing` is the **nearest-neighbour distance** in every shape: no two dancers are closer
//! than it, and each dancer has a neighbour exactly that far away. group.md samples it from
//! 0.9–1.8 m; anything from [`MIN_SEPARATION_M`] up is accepted, below it the template itself
//! would collide. Every template is centred (centroid at the origin, the stage centre) and its
//! slots are listed left to right as the audience sees them ([`order_left_to_right`]), so slot
//! order means the same thing for every shape; [`super::assign`] maps dancers onto slots.
//!
//! Shapes are defined for 1 to [`MAX_DANCERS`] dancers. One dancer stands at the centre in
//! every shape. Small groups cannot show every figure; those cases degrade to the figure the
//! shape shrinks to, never to an error:
//! - **2 dancers**: `v`, `inverted_v`, `triangle`, `diamond`, `circle` and `arc` are the pair
//!   side by side (a `line`); `two_rows` is a diagonal pair (one front, one back, half a
//!   spacing apart in x); `column` and `cluster` keep their own meaning.
//! - **3 dancers**: `diamond` is the `triangle` (its front three corners), and so is
//!   `two_rows` (two at the back, one in their gap); `circle` is the triangle the other way
//!   round (an edge towards the audience).

use super::{MIN_SEPARATION_M, StagePos, closest_pair, order_left_to_right};
use std::f64::consts::{FRAC_1_SQRT_2, PI};
use std::fmt;
use std::str::FromStr;

/// The largest group the templates are defined for: group.md §4's `N_max` = 5 (GCD's
/// `max_persons`).
pub const MAX_DANCERS: usize = 5;

/// Half-angle of the V between each arm and the stage's depth axis: 45°, a right angle at the
/// point, so the two dancers nearest the point stay √2 spacings apart (ours; group.md names the
/// shape only).
const V_HALF_ANGLE: f64 = PI / 4.0;

/// Angle an arc of dancers spans, seen from its centre: 120°, a shallow bowl open to the
/// audience (ours). Under 180°, so a dancer's nearest neighbours are its arc neighbours.
const ARC_SPAN: f64 = 2.0 * PI / 3.0;

/// The golden angle, `π(3 − √5)`, of Vogel's sunflower spiral (Vogel 1979), used for the
/// cluster: it packs points evenly without any row, line or symmetry a figure would have.
const GOLDEN_ANGLE: f64 = 2.399_963_229_728_653;

/// A named formation template.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Shape {
    /// Side by side across the stage.
    Line,
    /// One behind another, front to back.
    Column,
    /// A V with its point downstage, towards the audience.
    V,
    /// A V with its point upstage.
    InvertedV,
    /// A filled triangle with a point downstage.
    Triangle,
    /// A diamond (a square on its corner; with 5, a plus with a dancer in the middle).
    Diamond,
    /// Evenly round a circle, an edge towards the audience so nobody stands behind anybody.
    Circle,
    /// An arc open to the audience, its ends downstage.
    Arc,
    /// Two staggered rows: the front row stands in the back row's gaps.
    TwoRows,
    /// A loose huddle (Vogel's sunflower spiral), irregular on purpose.
    Cluster,
}

/// Why a template cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ShapeError {
    #[error("{shape}: {n} dancers; the formation templates are defined for up to {MAX_DANCERS}")]
    TooManyDancers { shape: Shape, n: usize },
    #[error(
        "spacing {spacing} m: must be a finite number of metres no smaller than {MIN_SEPARATION_M} \
         (closer dancers collide)"
    )]
    BadSpacing { spacing: f64 },
    #[error(
        "unknown formation shape {0:?} (known: {known})",
        known = Shape::ALL.map(Shape::name).join(", ")
    )]
    UnknownName(String),
}

impl Shape {
    /// Every shape, in the order of group.md §4.3's list.
    pub const ALL: [Shape; 10] = [
        Shape::Line,
        Shape::Column,
        Shape::V,
        Shape::InvertedV,
        Shape::Triangle,
        Shape::Diamond,
        Shape::Circle,
        Shape::Arc,
        Shape::TwoRows,
        Shape::Cluster,
    ];

    /// The lowercase snake-case name used on the command line and in logs.
    pub fn name(self) -> &'static str {
        match self {
            Shape::Line => "line",
            Shape::Column => "column",
            Shape::V => "v",
            Shape::InvertedV => "inverted_v",
            Shape::Triangle => "triangle",
            Shape::Diamond => "diamond",
            Shape::Circle => "circle",
            Shape::Arc => "arc",
            Shape::TwoRows => "two_rows",
            Shape::Cluster => "cluster",
        }
    }
}

impl fmt::Display for Shape {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Shape {
    type Err = ShapeError;

    fn from_str(s: &str) -> Result<Shape, ShapeError> {
        Shape::ALL
            .into_iter()
            .find(|shape| shape.name() == s)
            .ok_or_else(|| ShapeError::UnknownName(s.to_string()))
    }
}

/// The slots of `shape` for `n` dancers at `spacing` metres (module docs), centred and listed
/// left to right.
pub fn positions(shape: Shape, n: usize, spacing: f64) -> Result<Vec<StagePos>, ShapeError> {
    if !(spacing.is_finite() && spacing >= MIN_SEPARATION_M) {
        return Err(ShapeError::BadSpacing { spacing });
    }
    if n > MAX_DANCERS {
        return Err(ShapeError::TooManyDancers { shape, n });
    }
    let raw = if n <= 1 {
        vec![[0.0, 0.0]; n]
    } else {
        unit_positions(shape, n)
    };
    let centroid = raw
        .iter()
        .fold([0.0, 0.0], |c, p| [c[0] + p[0], c[1] + p[1]]);
    let count = n.max(1) as f64;
    let (cx, cz) = (centroid[0] / count, centroid[1] / count);
    // `+ 0.0` turns −0.0 into 0.0, so logged and written slots never show "-0".
    let centred: Vec<StagePos> = raw
        .iter()
        .map(|p| [(p[0] - cx) * spacing + 0.0, (p[1] - cz) * spacing + 0.0])
        .collect();
    Ok(order_left_to_right(&centred)
        .into_iter()
        .map(|i| centred[i])
        .collect())
}

/// The shape at unit spacing for 2..=MAX_DANCERS dancers, not yet centred.
fn unit_positions(shape: Shape, n: usize) -> Vec<StagePos> {
    /// Row depth of a triangular lattice at unit spacing (√3/2).
    const H: f64 = 0.866_025_403_784_438_6;
    match (shape, n) {
        (Shape::Line, _)
        | (Shape::V | Shape::InvertedV | Shape::Triangle | Shape::Diamond, 2)
        | (Shape::Circle | Shape::Arc, 2) => row(n, 0.0, 0.0),
        (Shape::Column, _) => (0..n).map(|i| [0.0, -(i as f64)]).collect(),
        (Shape::V, _) => v(n),
        (Shape::InvertedV, _) => v(n).into_iter().map(|[x, z]| [x, -z]).collect(),
        // Equilateral: one in front of two.
        (Shape::Triangle | Shape::Diamond, 3) => vec![[0.0, H], [-0.5, 0.0], [0.5, 0.0]],
        // A wedge: one a spacing in front of the middle of three.
        (Shape::Triangle, 4) => vec![[0.0, 1.0], [-1.0, 0.0], [0.0, 0.0], [1.0, 0.0]],
        // The triangular lattice's 1-2-3 rows without the back centre: the corners and the
        // side midpoints of a triangle two spacings wide.
        (Shape::Triangle, _) => vec![[0.0, 2.0 * H], [-0.5, H], [0.5, H], [-1.0, 0.0], [1.0, 0.0]],
        // A square on its corner, unit sides.
        (Shape::Diamond, 4) => {
            let a = FRAC_1_SQRT_2;
            vec![[0.0, a], [-a, 0.0], [a, 0.0], [0.0, -a]]
        }
        // A plus: the centre dancer a spacing from each corner.
        (Shape::Diamond, _) => vec![[0.0, 1.0], [-1.0, 0.0], [0.0, 0.0], [1.0, 0.0], [0.0, -1.0]],
        (Shape::Circle, _) => circle(n),
        (Shape::Arc, _) => arc(n),
        (Shape::TwoRows, _) => two_rows(n, H),
        (Shape::Cluster, _) => sunflower(n),
    }
}

/// `n` dancers one spacing apart along x, centred on `x0`, at depth `z`.
fn row(n: usize, x0: f64, z: f64) -> Vec<StagePos> {
    let half = (n as f64 - 1.0) / 2.0;
    (0..n).map(|i| [x0 + i as f64 - half, z]).collect()
}

/// A point dancer with arms going back; an even count leaves the point empty, its two nearest
/// dancers a spacing apart.
fn v(n: usize) -> Vec<StagePos> {
    let (sx, sz) = (V_HALF_ANGLE.sin(), -V_HALF_ANGLE.cos());
    let odd = n % 2 == 1;
    let mut out = if odd { vec![[0.0, 0.0]] } else { Vec::new() };
    for k in 0..n / 2 {
        let along = if odd { k as f64 + 1.0 } else { k as f64 };
        let x = if odd { 0.0 } else { 0.5 } + along * sx;
        out.push([-x, along * sz]);
        out.push([x, along * sz]);
    }
    out
}

/// A regular polygon of unit sides with its front edge parallel to the audience.
fn circle(n: usize) -> Vec<StagePos> {
    let step = 2.0 * PI / n as f64;
    let radius = 0.5 / (step / 2.0).sin();
    (0..n)
        .map(|i| {
            let angle = PI / 2.0 + step / 2.0 + i as f64 * step;
            [radius * angle.cos(), radius * angle.sin()]
        })
        .collect()
}

/// Dancers at unit chords on an [`ARC_SPAN`] arc whose centre is downstage of them.
fn arc(n: usize) -> Vec<StagePos> {
    let step = ARC_SPAN / (n as f64 - 1.0);
    let radius = 0.5 / (step / 2.0).sin();
    (0..n)
        .map(|i| {
            let angle = -ARC_SPAN / 2.0 + i as f64 * step;
            [radius * angle.sin(), -radius * angle.cos()]
        })
        .collect()
}

/// A back row of ⌈n/2⌉ and a front row of ⌊n/2⌋ in its gaps, rows `h` apart; equal rows are
/// offset by half a spacing.
fn two_rows(n: usize, h: f64) -> Vec<StagePos> {
    let (back, front) = (n.div_ceil(2), n / 2);
    let shift = if back == front { 0.5 } else { 0.0 };
    let mut out = row(back, 0.0, 0.0);
    out.extend(row(front, shift, h));
    out
}

/// Vogel's spiral (`r = √(k + ½)`, `θ = k · golden angle`), scaled so its closest pair is one
/// spacing apart.
fn sunflower(n: usize) -> Vec<StagePos> {
    let raw: Vec<StagePos> = (0..n)
        .map(|k| {
            let (r, theta) = ((k as f64 + 0.5).sqrt(), k as f64 * GOLDEN_ANGLE);
            [r * theta.cos(), r * theta.sin()]
        })
        .collect();
    let closest = closest_pair(&raw).map_or(1.0, |p| p.distance);
    raw.iter()
        .map(|p| [p[0] / closest, p[1] / closest])
        .collect()
}
