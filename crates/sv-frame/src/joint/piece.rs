//! Strip pieces in the joint solve: a piece's flat length, as the strips stage will lay it
//! out, held to the sheet it is cut from (docs/geometry.md 6.1, 6.5).

use sv_geom::{segment_closest, Point3, Real, Vector2};

use super::problem::{Problem, Row};
use super::unit::{UnitPoints, INPUTS};

/// A strip piece in the solve: its units in strip order and the joins between them.
#[derive(Clone, Debug)]
pub(super) struct Piece {
    pub units: Vec<usize>,
    pub joins: Vec<Join>,
}

/// The join of units `j` and `j + 1` of a piece: a bridge at its link's joint point.
#[derive(Clone, Copy, Debug)]
pub(super) struct Join {
    /// The link.
    pub link: usize,
    /// The facing sides of units `j` and `j + 1`.
    pub sides: [usize; 2],
    /// The link's first unit is unit `j` (else `j + 1`).
    pub forward: bool,
    /// Where the joint point lies along the first unit's side (0 to 1).
    pub s: Real,
}

/// A strip piece laid flat as the strips stage lays it (`sv_strips`, `place_next`): every
/// tile in its own plane, each next tile's facing side against the one before, running the
/// opposite way, the two meeting at the joint point (on the link's first unit at `s`, on
/// the other where its side comes closest to that point); its extent along the line from
/// the first tile's centre to the last's (mm).
pub(super) fn flat_length(tiles: &[[Point3; 4]], joins: &[Join]) -> Real {
    let flat = |q: &[Point3; 4]| -> [Vector2; 4] {
        let n = (q[2] - q[0]).cross(&(q[3] - q[1]));
        let e1 = (q[1] - q[0]).normalize();
        let e2 = n.normalize().cross(&e1);
        q.map(|p| Vector2::new((p - q[0]).dot(&e1), (p - q[0]).dot(&e2)))
    };
    let mut placed = vec![flat(&tiles[0])];
    for (j, join) in joins.iter().enumerate() {
        let [k, m] = join.sides;
        let (prev, next) = (&tiles[j], &tiles[j + 1]);
        let (ends_k, ends_m) = ([prev[k], prev[(k + 1) % 4]], [next[m], next[(m + 1) % 4]]);
        // the joint point's place along each side
        let (sk, sm) = if join.forward {
            let w = ends_k[0] + (ends_k[1] - ends_k[0]) * join.s;
            (join.s, segment_closest(&w, &w, &ends_m[0], &ends_m[1]).t)
        } else {
            let w = ends_m[0] + (ends_m[1] - ends_m[0]) * join.s;
            (segment_closest(&w, &w, &ends_k[0], &ends_k[1]).t, join.s)
        };
        let (a, b) = (placed[j][k], placed[j][(k + 1) % 4]);
        let local = flat(next);
        let (c, d) = (local[m], local[(m + 1) % 4]);
        // turn c -> d onto b -> a, then the joint points onto each other
        let (from, to) = ((d - c).normalize(), (a - b).normalize());
        let (cos, sin) = (from.dot(&to), from.x * to.y - from.y * to.x);
        let turn = |v: Vector2| Vector2::new(cos * v.x - sin * v.y, sin * v.x + cos * v.y);
        let shift = (a + (b - a) * sk) - turn(c + (d - c) * sm);
        placed.push(local.map(|v| turn(v) + shift));
    }
    let centre = |q: &[Vector2; 4]| (q[0] + q[1] + q[2] + q[3]) / 4.0;
    let axis = (centre(&placed[placed.len() - 1]) - centre(&placed[0])).normalize();
    let (lo, hi) = placed
        .iter()
        .flatten()
        .map(|v| v.dot(&axis))
        .fold((Real::INFINITY, Real::NEG_INFINITY), |(lo, hi), t| {
            (lo.min(t), hi.max(t))
        });
    hi - lo
}

impl Problem<'_> {
    /// A strip piece's tiles and joins at `x`.
    fn piece_at(
        &self,
        piece: &Piece,
        x: &[Real],
        units: &[UnitPoints],
    ) -> (Vec<[Point3; 4]>, Vec<Join>) {
        let scale = self.model.scale;
        let tiles = piece.units.iter().map(|&f| units[f].primary()).collect();
        let joins = piece
            .joins
            .iter()
            .map(|j| Join {
                s: x[self.joint_columns[j.link]] / scale,
                ..*j
            })
            .collect();
        (tiles, joins)
    }

    /// A strip piece's flat length ([`flat_length`]) at `x`.
    pub(super) fn piece_length(&self, piece: &Piece, x: &[Real], units: &[UnitPoints]) -> Real {
        let (tiles, joins) = self.piece_at(piece, x, units);
        flat_length(&tiles, &joins)
    }

    /// The gradient of a piece's flat length at `x` into `row`: its columns always, in the
    /// same order, and their values only if `values` (else zeros).
    pub(super) fn piece_gradient(
        &self,
        piece: &Piece,
        x: &[Real],
        units: &[UnitPoints],
        values: bool,
        row: &mut Row,
    ) {
        let scale = self.model.scale;
        let (mut tiles, mut joins) = self.piece_at(piece, x, units);
        let h = 1e-4;
        for (n, &f) in piece.units.iter().enumerate() {
            let Some(d) = &units[f].d else {
                continue;
            };
            if !values {
                for i in 0..INPUTS {
                    row.add(self.column(f, i), 0.0);
                }
                continue;
            }
            for p in 0..4 {
                for c in 0..3 {
                    let keep = tiles[n][p][c];
                    tiles[n][p][c] = keep + h;
                    let up = flat_length(&tiles, &joins);
                    tiles[n][p][c] = keep - h;
                    let down = flat_length(&tiles, &joins);
                    tiles[n][p][c] = keep;
                    let g = (up - down) / (2.0 * h);
                    for i in 0..INPUTS {
                        row.add(self.column(f, i), g * d[p][i][c]);
                    }
                }
            }
        }
        for j in 0..joins.len() {
            let col = self.joint_columns[joins[j].link];
            if !values {
                row.add(col, 0.0);
                continue;
            }
            let keep = joins[j].s;
            let h = 1e-6;
            joins[j].s = keep + h;
            let up = flat_length(&tiles, &joins);
            joins[j].s = keep - h;
            let down = flat_length(&tiles, &joins);
            joins[j].s = keep;
            row.add(col, (up - down) / (2.0 * h) / scale);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sv_geom::Vector3;

    /// A square of side `a` in the plane through `o` spanned by `u` (along the strip) and
    /// `v`, corners counter-clockwise from `o`.
    fn square(o: Point3, u: Vector3, v: Vector3, a: Real) -> [Point3; 4] {
        [o, o + u * a, o + u * a + v * a, o + v * a]
    }

    #[test]
    fn a_folded_row_of_squares_lies_flat_at_its_full_length() {
        // three 100 mm squares joined side to side, folded 30 and -50 degrees about their
        // joints: flat again they are 300 mm long whatever the folds
        let (x, y) = (Vector3::x(), Vector3::y());
        let t1 = Vector3::new(30f64.to_radians().cos(), 0.0, 30f64.to_radians().sin());
        let t2 = Vector3::new(
            (-20f64).to_radians().cos(),
            0.0,
            (-20f64).to_radians().sin(),
        );
        let a = square(Point3::origin(), x, y, 100.0);
        let b = square(a[1], t1, y, 100.0);
        let c = square(b[1], t2, y, 100.0);
        // joined at side 1 of the one before and side 3 of the next, the joint a third along
        let joins = |forward| {
            [0, 1].map(|link| Join {
                link,
                sides: [1, 3],
                forward,
                s: 1.0 / 3.0,
            })
        };
        for forward in [true, false] {
            let l = flat_length(&[a, b, c], &joins(forward));
            assert!((l - 300.0).abs() < 1e-9, "{l}");
        }
        // the middle square 10 mm longer along the strip: 310
        let b = [b[0], b[1] + t1 * 10.0, b[2] + t1 * 10.0, b[3]];
        let c = square(b[1], t2, y, 100.0);
        let l = flat_length(&[a, b, c], &joins(true));
        assert!((l - 310.0).abs() < 1e-9, "{l}");
    }
}
