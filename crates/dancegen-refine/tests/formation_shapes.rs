//! Formation templates: centred, separated, named, and degrading as documented.

use dancegen_refine::formation::shapes::{MAX_DANCERS, Shape, ShapeError, positions};
use dancegen_refine::formation::{MIN_SEPARATION_M, closest_pair, order_left_to_right};

#[test]
fn every_shape_is_centred_and_keeps_its_spacing() {
    // group.md §4.3 samples spacing from 0.9–1.8 m; 0.45 is the smallest accepted.
    for spacing in [MIN_SEPARATION_M, 0.9, 1.3, 1.8] {
        for shape in Shape::ALL {
            for n in 0..=MAX_DANCERS {
                let slots = positions(shape, n, spacing).unwrap();
                assert_eq!(slots.len(), n, "{shape} {n}");
                let centroid = slots
                    .iter()
                    .fold([0.0, 0.0], |c, p| [c[0] + p[0], c[1] + p[1]]);
                assert!(
                    centroid[0].abs() < 1e-12 && centroid[1].abs() < 1e-12,
                    "{shape} {n}: centroid {centroid:?}"
                );
                if let Some(pair) = closest_pair(&slots) {
                    // Spacing is the nearest-neighbour distance, exactly (rounding aside).
                    assert!(
                        (pair.distance - spacing).abs() < 1e-9,
                        "{shape} n={n} spacing={spacing}: closest {pair:?}"
                    );
                    assert!(pair.distance >= MIN_SEPARATION_M - 1e-9);
                }
                let order = order_left_to_right(&slots);
                assert_eq!(
                    order,
                    (0..n).collect::<Vec<_>>(),
                    "{shape} {n}: slots left to right"
                );
            }
        }
    }
}

#[test]
fn shapes_look_like_their_names() {
    let at = |shape, n| positions(shape, n, 1.0).unwrap();
    // Line: one row across; column: one file front to back.
    assert!(at(Shape::Line, 4).iter().all(|p| p[1].abs() < 1e-12));
    assert!(at(Shape::Column, 4).iter().all(|p| p[0].abs() < 1e-12));
    // V: the middle dancer is the most downstage (+z); inverted V: the most upstage.
    let v = at(Shape::V, 5);
    assert!(v.iter().all(|p| p[1] <= v[2][1]));
    let inverted = at(Shape::InvertedV, 5);
    assert!(inverted.iter().all(|p| p[1] >= inverted[2][1]));
    // Triangle of 3: one in front of two.
    let triangle = at(Shape::Triangle, 3);
    assert!(triangle[1][1] > triangle[0][1] && (triangle[0][1] - triangle[2][1]).abs() < 1e-12);
    // Diamond of 5: a plus with a dancer in the middle.
    assert!(
        at(Shape::Diamond, 5)
            .iter()
            .any(|p| p[0].abs() < 1e-12 && p[1].abs() < 1e-12)
    );
    // Circle: every dancer equally far from the centre.
    let circle = at(Shape::Circle, 5);
    let r = circle[0][0].hypot(circle[0][1]);
    assert!(circle.iter().all(|p| (p[0].hypot(p[1]) - r).abs() < 1e-12));
    // Arc: open to the audience, its ends downstage of its middle.
    let arc = at(Shape::Arc, 5);
    assert!(arc[0][1] > arc[2][1] && arc[4][1] > arc[2][1]);
    // Two rows: two depths only.
    let rows = at(Shape::TwoRows, 5);
    let depths = rows
        .iter()
        .filter(|p| (p[1] - rows[0][1]).abs() > 1e-9)
        .count();
    assert!(depths == 2 || depths == 3, "{rows:?}");
    // One dancer stands at the centre whatever the shape.
    for shape in Shape::ALL {
        assert_eq!(at(shape, 1), vec![[0.0, 0.0]]);
    }
}

#[test]
fn small_groups_degrade_as_documented() {
    let at = |shape, n| positions(shape, n, 0.9).unwrap();
    for shape in [
        Shape::V,
        Shape::InvertedV,
        Shape::Triangle,
        Shape::Diamond,
        Shape::Circle,
        Shape::Arc,
    ] {
        assert_eq!(at(shape, 2), at(Shape::Line, 2), "{shape}");
    }
    assert_eq!(at(Shape::Diamond, 3), at(Shape::Triangle, 3));
    assert_eq!(at(Shape::TwoRows, 3), at(Shape::Triangle, 3));
    let pair = at(Shape::TwoRows, 2);
    assert!((pair[0][0] - pair[1][0]).abs() > 0.4 && (pair[0][1] - pair[1][1]).abs() > 0.7);
}

#[test]
fn names_round_trip_and_bad_requests_are_errors() {
    for shape in Shape::ALL {
        assert_eq!(shape.name().parse::<Shape>().unwrap(), shape);
        assert_eq!(shape.to_string(), shape.name());
    }
    assert_eq!("two_rows".parse::<Shape>().unwrap(), Shape::TwoRows);
    let unknown = "hexagon".parse::<Shape>().unwrap_err();
    assert!(unknown.to_string().contains("hexagon") && unknown.to_string().contains("two_rows"));
    assert_eq!(
        positions(Shape::Line, 6, 1.0),
        Err(ShapeError::TooManyDancers {
            shape: Shape::Line,
            n: 6
        })
    );
    for spacing in [0.3, -1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            positions(Shape::Circle, 3, spacing),
            Err(ShapeError::BadSpacing { .. })
        ));
    }
}
