//! A frame as an OBJ file to look at in Rhino (or any OBJ viewer).

use std::fmt::Write as _;

use sv_frame::FrameFile;

use crate::text::real;

/// `file` as OBJ text for Rhino: three objects (`o`) that are also groups (`g`):
///
/// - `hubs`: one quad face per unit, its hub corners `s_0..s_3`;
/// - `primary`: one quad face per unit, its primary tile corners `r_0..r_3`;
/// - `legs`: one line element `l` per leg, leg `i` of a unit joining hub corner `s_i` to
///   primary corner `r_{(i+1) % 4}` (model.md sec. 3).
///
/// Where the frame has the parts as cut (a build's frame), also `hub_plates` and
/// `legs_as_cut` ([`as_cut`]): the model's hubs are the zero-width idealisation, up to tens
/// of millimetres off the plates as cut, so a lap measured in Rhino is measured on those.
///
/// Model size (no expansion), mm, right-handed, Z up; the header comment says so, since OBJ
/// has no unit field (import into a millimetre document, without a Y-up swap). Vertex
/// numbers are global and 1-based: unit `u`'s hub corner `i` is vertex `4u + i + 1`, its
/// primary corner `i` is vertex `4U + 4u + i + 1` for `U` units. A comment before each face
/// names the unit's `id` and strip.
pub fn frame_to_obj(file: &FrameFile) -> String {
    let n = file.units.len();
    let mut out = String::with_capacity(n * 400 + 256);
    let _ = writeln!(
        out,
        "# spin-valence frame ({} v{})",
        file.format, file.version
    );
    out.push_str("# units: mm (import into a millimetre document)\n");
    out.push_str("# axes: right-handed, Z up (do not swap Y and Z on import)\n");
    let _ = writeln!(
        out,
        "# {n} units: hubs and primary tiles as quads (model size), legs as lines hub corner i -> primary corner (i+1)%4"
    );
    let _ = writeln!(
        out,
        "# spin angle {} rad, expansion {}",
        real(file.params.spin_angle),
        real(file.params.expansion)
    );
    for unit in &file.units {
        for p in &unit.hub {
            let _ = writeln!(out, "v {} {} {}", real(p[0]), real(p[1]), real(p[2]));
        }
    }
    for unit in &file.units {
        for p in &unit.primary {
            let _ = writeln!(out, "v {} {} {}", real(p[0]), real(p[1]), real(p[2]));
        }
    }
    let hub = |u: usize, i: usize| 4 * u + i + 1;
    let primary = |u: usize, i: usize| 4 * n + 4 * u + i + 1;
    for (group, corner) in [
        ("hubs", &hub as &dyn Fn(usize, usize) -> usize),
        ("primary", &primary),
    ] {
        let _ = writeln!(out, "o {group}\ng {group}");
        for (u, unit) in file.units.iter().enumerate() {
            let _ = writeln!(
                out,
                "# unit {} (strip {})\nf {} {} {} {}",
                one_line(&unit.id),
                one_line(&unit.strip),
                corner(u, 0),
                corner(u, 1),
                corner(u, 2),
                corner(u, 3)
            );
        }
    }
    out.push_str("o legs\ng legs\n");
    for u in 0..n {
        for i in 0..4 {
            let _ = writeln!(out, "l {} {}", hub(u, i), primary(u, (i + 1) % 4));
        }
    }
    as_cut(file, &mut out);
    out
}

/// The parts as cut, where the frame has them (every unit its `hub_plate`, its `pins`):
/// `hub_plates`, one quad per unit (the plate as cut, on which a lap is measured), and
/// `legs_as_cut`, one line per leg from its pin on the hub plate to its pin on the primary
/// plate. Their vertices follow the model's: every unit's four hub plate corners, then
/// every unit's legs, each its hub pin then its rim pin.
fn as_cut(file: &FrameFile, out: &mut String) {
    let n = file.units.len();
    let plates: Option<Vec<_>> = file.units.iter().map(|u| u.hub_plate).collect();
    let pins: Option<Vec<_>> = file.units.iter().map(|u| u.pins.as_ref()).collect();
    let mut next = 8 * n + 1;
    let mut vertex = |out: &mut String, p: &[f64; 3]| {
        let _ = writeln!(out, "v {} {} {}", real(p[0]), real(p[1]), real(p[2]));
        next += 1;
        next - 1
    };
    if let Some(plates) = plates {
        out.push_str("# hub plates as cut (laps are measured on these)\n");
        let corners: Vec<[usize; 4]> = plates
            .iter()
            .map(|plate| plate.each_ref().map(|p| vertex(out, p)))
            .collect();
        out.push_str("o hub_plates\ng hub_plates\n");
        for (unit, c) in file.units.iter().zip(&corners) {
            let _ = writeln!(
                out,
                "# unit {}\nf {} {} {} {}",
                one_line(&unit.id),
                c[0],
                c[1],
                c[2],
                c[3]
            );
        }
    }
    if let Some(pins) = pins {
        out.push_str("# legs as cut: pin on the hub plate -> pin on the primary plate\n");
        let ends: Vec<[[usize; 2]; 4]> = pins
            .iter()
            .map(|p| std::array::from_fn(|j| [vertex(out, &p.hub[j]), vertex(out, &p.rim[j])]))
            .collect();
        out.push_str("o legs_as_cut\ng legs_as_cut\n");
        for legs in &ends {
            for [a, b] in legs {
                let _ = writeln!(out, "l {a} {b}");
            }
        }
    }
}

/// A label made safe for a comment line.
fn one_line(label: &str) -> String {
    label.replace(['\n', '\r'], " ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame_json::tests::two_units;
    use sv_geom::Point3;

    /// The vertices, and the `f` / `l` elements per object, of OBJ text.
    struct Parsed {
        vertices: Vec<Point3>,
        faces: Vec<(String, Vec<usize>)>,
        lines: Vec<(String, [usize; 2])>,
    }

    fn parse(text: &str) -> Parsed {
        let mut p = Parsed {
            vertices: Vec::new(),
            faces: Vec::new(),
            lines: Vec::new(),
        };
        let mut object = String::new();
        for line in text.lines() {
            let t: Vec<&str> = line.split_whitespace().collect();
            match t.first().copied() {
                Some("v") => p.vertices.push(Point3::new(
                    t[1].parse().unwrap(),
                    t[2].parse().unwrap(),
                    t[3].parse().unwrap(),
                )),
                Some("o") => object = t[1].to_string(),
                Some("f") => p.faces.push((
                    object.clone(),
                    t[1..]
                        .iter()
                        .map(|s| s.parse::<usize>().unwrap() - 1)
                        .collect(),
                )),
                Some("l") => p.lines.push((
                    object.clone(),
                    [
                        t[1].parse::<usize>().unwrap() - 1,
                        t[2].parse::<usize>().unwrap() - 1,
                    ],
                )),
                _ => {}
            }
        }
        p
    }

    fn point(a: [f64; 3]) -> Point3 {
        Point3::new(a[0], a[1], a[2])
    }

    #[test]
    fn objects_faces_and_legs_follow_the_model() {
        let file = two_units();
        let text = frame_to_obj(&file);
        assert!(
            text.contains("# units: mm") && text.contains("Z up"),
            "{text}"
        );
        for g in ["hubs", "primary", "legs"] {
            assert!(text.contains(&format!("o {g}\ng {g}\n")), "{g}");
        }
        let p = parse(&text);
        assert_eq!(p.vertices.len(), 16);
        assert_eq!(p.faces.len(), 4);
        assert_eq!(p.lines.len(), 8);
        for (u, unit) in file.units.iter().enumerate() {
            let (g, hub) = &p.faces[u];
            assert_eq!(g, "hubs");
            let got: Vec<Point3> = hub.iter().map(|&v| p.vertices[v]).collect();
            assert_eq!(got, unit.hub.map(point).to_vec());
            let (g, prim) = &p.faces[2 + u];
            assert_eq!(g, "primary");
            let got: Vec<Point3> = prim.iter().map(|&v| p.vertices[v]).collect();
            assert_eq!(got, unit.primary.map(point).to_vec());
            for i in 0..4 {
                let (g, [a, b]) = &p.lines[4 * u + i];
                assert_eq!(g, "legs");
                assert_eq!(p.vertices[*a], point(unit.hub[i]));
                assert_eq!(p.vertices[*b], point(unit.primary[(i + 1) % 4]));
            }
        }
    }

    #[test]
    fn legs_of_a_solved_frame_are_as_long_as_primary_sides() {
        let mesh = sv_frame::QuadMesh::sphere_cap(3, 2, 3000.0, 300.0);
        let solved = sv_frame::solve(&mesh, &Default::default(), &mut |_| {}).unwrap();
        let file = solved.to_frame_file(&mesh);
        let p = parse(&frame_to_obj(&file));
        let legs: Vec<_> = p.lines.iter().filter(|(g, _)| g == "legs").collect();
        assert_eq!(legs.len(), 4 * file.units.len());
        for (u, unit) in file.units.iter().enumerate() {
            for i in 0..4 {
                let [a, b] = legs[4 * u + i].1;
                let leg = (p.vertices[a] - p.vertices[b]).norm();
                let side = (point(unit.primary[i]) - point(unit.primary[(i + 1) % 4])).norm();
                assert!(
                    (leg - side).abs() <= 1e-9 * side,
                    "unit {u} leg {i}: {leg} vs side {side}"
                );
            }
        }
    }

    #[test]
    fn a_frame_with_its_parts_as_cut_draws_them_too() {
        let mut file = two_units();
        let model = parse(&frame_to_obj(&file));
        assert!(model.faces.iter().all(|(g, _)| g != "hub_plates"));
        for (u, unit) in file.units.iter_mut().enumerate() {
            let shift = |p: [f64; 3], d: f64| [p[0] + d, p[1] - d, p[2] + 0.5 * d];
            unit.hub_plate = Some(unit.hub.map(|p| shift(p, 7.0 + u as f64)));
            unit.pins = Some(sv_frame::LegPins {
                hub: unit.hub.map(|p| shift(p, 3.0)),
                rim: unit.primary.map(|p| shift(p, -2.0)),
                length: [0.0; 4],
            });
        }
        let text = frame_to_obj(&file);
        let p = parse(&text);
        // the model first, as before; then 4 plate corners and 8 pins per unit
        assert_eq!(p.vertices[..16], model.vertices[..]);
        assert_eq!(p.vertices.len(), 16 + 2 * 12);
        let plates: Vec<_> = p.faces.iter().filter(|(g, _)| g == "hub_plates").collect();
        let legs: Vec<_> = p.lines.iter().filter(|(g, _)| g == "legs_as_cut").collect();
        assert_eq!((plates.len(), legs.len()), (2, 8));
        for (u, unit) in file.units.iter().enumerate() {
            let got: Vec<Point3> = plates[u].1.iter().map(|&v| p.vertices[v]).collect();
            assert_eq!(got, unit.hub_plate.unwrap().map(point).to_vec());
            let pins = unit.pins.as_ref().unwrap();
            for j in 0..4 {
                let [a, b] = legs[4 * u + j].1;
                assert_eq!(
                    (p.vertices[a], p.vertices[b]),
                    (point(pins.hub[j]), point(pins.rim[j]))
                );
            }
        }
    }

    #[test]
    fn the_quad_reader_reads_the_hub_and_primary_faces() {
        let file = two_units();
        let mesh = crate::read_quad_obj(&frame_to_obj(&file), "frame.obj").unwrap();
        assert_eq!(mesh.faces.len(), 4);
        assert_eq!(mesh.vertices[..4], file.units[0].hub.map(point));
    }
}
