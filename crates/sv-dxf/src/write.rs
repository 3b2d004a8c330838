//! The DXF writer: ASCII R2000 (AC1015), `$INSUNITS` = 4 (mm), a complete skeleton
//! (HEADER, CLASSES, TABLES, BLOCKS, ENTITIES, OBJECTS with handles and owners, so that
//! ezdxf's auditor has nothing to fix), the shop layers, and entities in the order they are
//! added (a CAM cuts in file order unless told otherwise): closed LWPOLYLINEs with bulges
//! (arcs stay arcs), open LWPOLYLINEs, POINTs and TEXT.

use std::fmt::Write;

use sv_geom::Contour;

use crate::{LAYER_ETCH, LAYER_INFO, LAYER_INSIDE, LAYER_OUTSIDE};

/// Group-code writer with a handle counter.
struct Out {
    s: String,
    next: u32,
}

impl Out {
    fn pair(&mut self, code: i32, value: impl std::fmt::Display) {
        let _ = write!(self.s, "{code:>3}\n{value}\n");
    }
    fn real(&mut self, code: i32, v: f64) {
        // 1e-9 mm resolution, no exponent
        let v = if v.abs() < 5e-10 { 0.0 } else { v };
        let _ = write!(self.s, "{code:>3}\n{v:.9}\n");
    }
    fn handle(&mut self) -> String {
        let h = format!("{:X}", self.next);
        self.next += 1;
        h
    }
}

// fixed handles of the skeleton
const H_VPORT_TABLE: &str = "1";
const H_LTYPE_TABLE: &str = "2";
const H_LAYER_TABLE: &str = "3";
const H_STYLE_TABLE: &str = "4";
const H_VIEW_TABLE: &str = "5";
const H_UCS_TABLE: &str = "6";
const H_APPID_TABLE: &str = "7";
const H_DIMSTYLE_TABLE: &str = "8";
const H_BLOCK_RECORD_TABLE: &str = "9";
const H_ROOT_DICT: &str = "A";
const H_GROUP_DICT: &str = "B";
const H_LAYOUT_DICT: &str = "C";
const H_MODEL_BR: &str = "D";
const H_PAPER_BR: &str = "E";
const H_MODEL_LAYOUT: &str = "F";
const H_PAPER_LAYOUT: &str = "10";
const FIRST_FREE: u32 = 0x100;

fn table_head(o: &mut Out, name: &str, handle: &str, count: usize) {
    o.pair(0, "TABLE");
    o.pair(2, name);
    o.pair(5, handle);
    o.pair(330, "0");
    o.pair(100, "AcDbSymbolTable");
    o.pair(70, count);
}

/// The head of a BLOCK or ENDBLK record of `owner` (on paper space when `paper`).
fn block_head(o: &mut Out, kind: &str, owner: &str, paper: bool, subclass: &str) {
    let h = o.handle();
    o.pair(0, kind);
    o.pair(5, h);
    o.pair(330, owner);
    o.pair(100, "AcDbEntity");
    if paper {
        o.pair(67, 1);
    }
    o.pair(8, "0");
    o.pair(100, subclass);
}

fn record_head(o: &mut Out, kind: &str, owner: &str, subclass: &str) -> String {
    let h = o.handle();
    o.pair(0, kind);
    o.pair(5, &h);
    o.pair(330, owner);
    o.pair(100, "AcDbSymbolTableRecord");
    o.pair(100, subclass);
    h
}

/// The ENTITIES of one drawing, written in the order they are added (the CAM cuts in
/// file order unless told otherwise), then wrapped in a complete R2000 file by [`finish`].
///
/// ```
/// use sv_dxf::{Drawing, LAYER_OUTSIDE};
/// let mut d = Drawing::new();
/// d.contour(LAYER_OUTSIDE, &sv_geom::Contour::circle(0.0, 0.0, 10.0));
/// let text = d.finish();
/// assert!(text.contains("AC1015") && text.ends_with("EOF\n"));
/// // the header extents hold the circle
/// assert!(text.contains("$EXTMIN\n 10\n-10.000000000\n 20\n-10.000000000"));
/// ```
///
/// [`finish`]: Drawing::finish
pub struct Drawing {
    body: Out,
    /// the extents of everything drawn so far
    lo: [f64; 2],
    hi: [f64; 2],
}

impl Default for Drawing {
    fn default() -> Self {
        Self::new()
    }
}

impl Drawing {
    /// An empty drawing.
    pub fn new() -> Self {
        Self {
            body: Out {
                s: String::new(),
                next: FIRST_FREE,
            },
            lo: [f64::INFINITY; 2],
            hi: [f64::NEG_INFINITY; 2],
        }
    }

    fn grow(&mut self, p: [f64; 2]) {
        for k in 0..2 {
            self.lo[k] = self.lo[k].min(p[k]);
            self.hi[k] = self.hi[k].max(p[k]);
        }
    }

    fn entity(&mut self, kind: &str, layer: &str, subclass: &str) {
        let o = &mut self.body;
        let h = o.handle();
        o.pair(0, kind);
        o.pair(5, h);
        o.pair(330, H_MODEL_BR);
        o.pair(100, "AcDbEntity");
        o.pair(8, layer);
        o.pair(100, subclass);
    }

    /// An LWPOLYLINE through `points` (`[x, y, bulge of the segment leaving the point]`).
    fn polyline(
        &mut self,
        layer: &str,
        points: impl ExactSizeIterator<Item = [f64; 3]>,
        closed: bool,
    ) {
        self.entity("LWPOLYLINE", layer, "AcDbPolyline");
        let o = &mut self.body;
        o.pair(90, points.len());
        o.pair(70, if closed { 1 } else { 0 });
        o.real(43, 0.0);
        for p in points {
            o.real(10, p[0]);
            o.real(20, p[1]);
            if p[2] != 0.0 {
                o.real(42, p[2]);
            }
        }
    }

    /// A closed LWPOLYLINE with bulges: the contour as it is (same vertices, same
    /// direction; arcs stay arcs).
    pub fn contour(&mut self, layer: &str, contour: &Contour) {
        if let Some((lo, hi)) = contour.bounds() {
            self.grow(lo);
            self.grow(hi);
        }
        self.polyline(layer, contour.vertices.iter().map(|&v| v.into()), true);
    }

    /// An open polyline of straight segments.
    pub fn open_line(&mut self, layer: &str, pts: &[[f64; 2]]) {
        pts.iter().for_each(|&p| self.grow(p));
        self.polyline(layer, pts.iter().map(|p| [p[0], p[1], 0.0]), false);
    }

    /// A closed polygon of straight segments.
    pub fn polygon(&mut self, layer: &str, pts: &[[f64; 2]]) {
        pts.iter().for_each(|&p| self.grow(p));
        self.polyline(layer, pts.iter().map(|p| [p[0], p[1], 0.0]), true);
    }

    /// The box a TEXT of `height` at `at` may cover in a CAD program's font: one cap
    /// height per character wide (wider than any usual font), a third below the baseline.
    pub fn text_box(text: &str, at: [f64; 2], height: f64) -> ([f64; 2], [f64; 2]) {
        let width = height * text.chars().count() as f64;
        (
            [at[0], at[1] - height / 3.0],
            [at[0] + width, at[1] + 1.25 * height],
        )
    }

    /// A TEXT entity (style Standard) with its baseline starting at `at`, for people.
    pub fn text(&mut self, layer: &str, text: &str, at: [f64; 2], height: f64) {
        let (lo, hi) = Self::text_box(text, at, height);
        self.grow(lo);
        self.grow(hi);
        self.entity("TEXT", layer, "AcDbText");
        let o = &mut self.body;
        o.real(10, at[0]);
        o.real(20, at[1]);
        o.real(30, 0.0);
        o.real(40, height);
        o.pair(1, text);
        o.pair(7, "Standard");
        o.pair(100, "AcDbText");
    }

    /// A POINT entity.
    pub fn point(&mut self, layer: &str, at: [f64; 2]) {
        self.grow(at);
        self.entity("POINT", layer, "AcDbPoint");
        let o = &mut self.body;
        o.real(10, at[0]);
        o.real(20, at[1]);
        o.real(30, 0.0);
    }

    /// The complete DXF file, its header extents holding everything drawn.
    pub fn finish(self) -> String {
        let (ext_min, ext_max) = if self.lo[0] <= self.hi[0] {
            (self.lo, self.hi)
        } else {
            ([0.0; 2], [0.0; 2])
        };
        let entities = self.body.s;
        let seed = self.body.next;
        let mut o = Out {
            s: String::with_capacity(entities.len() + 8192),
            next: 0x11,
        };
        // HEADER
        o.pair(0, "SECTION");
        o.pair(2, "HEADER");
        o.pair(9, "$ACADVER");
        o.pair(1, "AC1015");
        o.pair(9, "$HANDSEED");
        o.pair(5, format!("{seed:X}"));
        o.pair(9, "$INSUNITS");
        o.pair(70, 4);
        o.pair(9, "$MEASUREMENT");
        o.pair(70, 1);
        o.pair(9, "$EXTMIN");
        o.real(10, ext_min[0]);
        o.real(20, ext_min[1]);
        o.real(30, 0.0);
        o.pair(9, "$EXTMAX");
        o.real(10, ext_max[0]);
        o.real(20, ext_max[1]);
        o.real(30, 0.0);
        o.pair(0, "ENDSEC");
        o.pair(0, "SECTION");
        o.pair(2, "CLASSES");
        o.pair(0, "ENDSEC");
        // TABLES
        o.pair(0, "SECTION");
        o.pair(2, "TABLES");
        table_head(&mut o, "VPORT", H_VPORT_TABLE, 1);
        record_head(&mut o, "VPORT", H_VPORT_TABLE, "AcDbViewportTableRecord");
        o.pair(2, "*Active");
        o.pair(70, 0);
        for (c, v) in [(10, 0.0), (20, 0.0), (11, 1.0), (21, 1.0)] {
            o.real(c, v);
        }
        o.real(12, (ext_min[0] + ext_max[0]) / 2.0);
        o.real(22, (ext_min[1] + ext_max[1]) / 2.0);
        o.real(40, (ext_max[1] - ext_min[1]).max(1.0) * 1.1);
        o.real(41, 2.0);
        o.pair(0, "ENDTAB");
        table_head(&mut o, "LTYPE", H_LTYPE_TABLE, 3);
        for name in ["ByBlock", "ByLayer", "Continuous"] {
            record_head(&mut o, "LTYPE", H_LTYPE_TABLE, "AcDbLinetypeTableRecord");
            o.pair(2, name);
            o.pair(70, 0);
            o.pair(
                3,
                if name == "Continuous" {
                    "Solid line"
                } else {
                    ""
                },
            );
            o.pair(72, 65);
            o.pair(73, 0);
            o.real(40, 0.0);
        }
        o.pair(0, "ENDTAB");
        let layers = [
            ("0", 7, true),
            (LAYER_OUTSIDE, 1, true),
            (LAYER_INSIDE, 5, true),
            (LAYER_ETCH, 3, true),
            (LAYER_INFO, 8, false),
        ];
        table_head(&mut o, "LAYER", H_LAYER_TABLE, layers.len());
        for (name, color, plot) in layers {
            record_head(&mut o, "LAYER", H_LAYER_TABLE, "AcDbLayerTableRecord");
            o.pair(2, name);
            o.pair(70, 0);
            o.pair(62, color);
            o.pair(6, "Continuous");
            o.pair(290, if plot { 1 } else { 0 });
            o.pair(370, -3);
        }
        o.pair(0, "ENDTAB");
        table_head(&mut o, "STYLE", H_STYLE_TABLE, 1);
        record_head(&mut o, "STYLE", H_STYLE_TABLE, "AcDbTextStyleTableRecord");
        o.pair(2, "Standard");
        o.pair(70, 0);
        o.real(40, 0.0);
        o.real(41, 1.0);
        o.real(50, 0.0);
        o.pair(71, 0);
        o.real(42, 2.5);
        o.pair(3, "txt");
        o.pair(4, "");
        o.pair(0, "ENDTAB");
        table_head(&mut o, "VIEW", H_VIEW_TABLE, 0);
        o.pair(0, "ENDTAB");
        table_head(&mut o, "UCS", H_UCS_TABLE, 0);
        o.pair(0, "ENDTAB");
        table_head(&mut o, "APPID", H_APPID_TABLE, 1);
        record_head(&mut o, "APPID", H_APPID_TABLE, "AcDbRegAppTableRecord");
        o.pair(2, "ACAD");
        o.pair(70, 0);
        o.pair(0, "ENDTAB");
        o.pair(0, "TABLE");
        o.pair(2, "DIMSTYLE");
        o.pair(5, H_DIMSTYLE_TABLE);
        o.pair(330, "0");
        o.pair(100, "AcDbSymbolTable");
        o.pair(70, 1);
        o.pair(100, "AcDbDimStyleTable");
        o.pair(71, 0);
        let h = o.handle();
        o.pair(0, "DIMSTYLE");
        o.pair(105, h);
        o.pair(330, H_DIMSTYLE_TABLE);
        o.pair(100, "AcDbSymbolTableRecord");
        o.pair(100, "AcDbDimStyleTableRecord");
        o.pair(2, "Standard");
        o.pair(70, 0);
        o.pair(0, "ENDTAB");
        table_head(&mut o, "BLOCK_RECORD", H_BLOCK_RECORD_TABLE, 2);
        for (h, name, layout) in [
            (H_MODEL_BR, "*Model_Space", H_MODEL_LAYOUT),
            (H_PAPER_BR, "*Paper_Space", H_PAPER_LAYOUT),
        ] {
            o.pair(0, "BLOCK_RECORD");
            o.pair(5, h);
            o.pair(330, H_BLOCK_RECORD_TABLE);
            o.pair(100, "AcDbSymbolTableRecord");
            o.pair(100, "AcDbBlockTableRecord");
            o.pair(2, name);
            o.pair(340, layout);
        }
        o.pair(0, "ENDTAB");
        o.pair(0, "ENDSEC");
        // BLOCKS
        o.pair(0, "SECTION");
        o.pair(2, "BLOCKS");
        for (owner, name, paper) in [
            (H_MODEL_BR, "*Model_Space", false),
            (H_PAPER_BR, "*Paper_Space", true),
        ] {
            block_head(&mut o, "BLOCK", owner, paper, "AcDbBlockBegin");
            o.pair(2, name);
            o.pair(70, 0);
            o.real(10, 0.0);
            o.real(20, 0.0);
            o.real(30, 0.0);
            o.pair(3, name);
            o.pair(1, "");
            block_head(&mut o, "ENDBLK", owner, paper, "AcDbBlockEnd");
        }
        o.pair(0, "ENDSEC");
        // ENTITIES
        o.pair(0, "SECTION");
        o.pair(2, "ENTITIES");
        o.s.push_str(&entities);
        o.pair(0, "ENDSEC");
        // OBJECTS
        o.pair(0, "SECTION");
        o.pair(2, "OBJECTS");
        o.pair(0, "DICTIONARY");
        o.pair(5, H_ROOT_DICT);
        o.pair(330, "0");
        o.pair(100, "AcDbDictionary");
        o.pair(281, 1);
        o.pair(3, "ACAD_GROUP");
        o.pair(350, H_GROUP_DICT);
        o.pair(3, "ACAD_LAYOUT");
        o.pair(350, H_LAYOUT_DICT);
        o.pair(0, "DICTIONARY");
        o.pair(5, H_GROUP_DICT);
        o.pair(330, H_ROOT_DICT);
        o.pair(100, "AcDbDictionary");
        o.pair(281, 1);
        o.pair(0, "DICTIONARY");
        o.pair(5, H_LAYOUT_DICT);
        o.pair(330, H_ROOT_DICT);
        o.pair(100, "AcDbDictionary");
        o.pair(281, 1);
        o.pair(3, "Layout1");
        o.pair(350, H_PAPER_LAYOUT);
        o.pair(3, "Model");
        o.pair(350, H_MODEL_LAYOUT);
        for (h, name, order, br) in [
            (H_MODEL_LAYOUT, "Model", 0, H_MODEL_BR),
            (H_PAPER_LAYOUT, "Layout1", 1, H_PAPER_BR),
        ] {
            o.pair(0, "LAYOUT");
            o.pair(5, h);
            o.pair(330, H_LAYOUT_DICT);
            o.pair(100, "AcDbPlotSettings");
            o.pair(1, "");
            o.pair(4, "A3");
            o.pair(6, "");
            for c in 40..=47 {
                o.real(c, 0.0);
            }
            o.real(48, 0.0);
            o.real(49, 0.0);
            o.real(140, 0.0);
            o.real(141, 0.0);
            o.real(142, 1.0);
            o.real(143, 1.0);
            o.pair(70, if order == 0 { 1712 } else { 688 });
            o.pair(72, 1);
            o.pair(73, 0);
            o.pair(74, 5);
            o.pair(7, "");
            o.pair(75, 16);
            o.real(147, 1.0);
            o.real(148, 0.0);
            o.real(149, 0.0);
            o.pair(100, "AcDbLayout");
            o.pair(1, name);
            o.pair(70, 1);
            o.pair(71, order);
            o.real(10, 0.0);
            o.real(20, 0.0);
            o.real(11, 420.0);
            o.real(21, 297.0);
            o.real(12, 0.0);
            o.real(22, 0.0);
            o.real(32, 0.0);
            o.real(14, ext_min[0]);
            o.real(24, ext_min[1]);
            o.real(34, 0.0);
            o.real(15, ext_max[0]);
            o.real(25, ext_max[1]);
            o.real(35, 0.0);
            o.real(146, 0.0);
            o.real(13, 0.0);
            o.real(23, 0.0);
            o.real(33, 0.0);
            o.real(16, 1.0);
            o.real(26, 0.0);
            o.real(36, 0.0);
            o.real(17, 0.0);
            o.real(27, 1.0);
            o.real(37, 0.0);
            o.pair(76, 0);
            o.pair(330, br);
        }
        o.pair(0, "ENDSEC");
        o.pair(0, "EOF");
        o.s
    }
}
