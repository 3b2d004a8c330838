//! What a layer holds, by its name: cut contours (outlines, holes, or either by
//! containment), etching, or nothing to cut (bend lines, construction, dimensions,
//! borders, our own `INFO`). Rules are case-insensitive glob patterns (`*`, `?`), the
//! user's before the defaults, the first match wins.

use std::fmt;
use std::str::FromStr;

/// What the entities of a layer are.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LayerRole {
    /// Part outlines (`OUTSIDE`).
    Outside,
    /// Holes of the outline around them (`INSIDE`).
    Inside,
    /// Cut contours, outline or hole by containment (layer `0` and every other layer).
    Cut,
    /// Etched marks: drawn with the part, not cut, not nested (`ETCH`).
    Etch,
    /// Not cut and not etched; the reason names what the layer holds ("bend lines").
    Skip(String),
}

impl fmt::Display for LayerRole {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LayerRole::Outside => f.write_str("outside"),
            LayerRole::Inside => f.write_str("inside"),
            LayerRole::Cut => f.write_str("cut"),
            LayerRole::Etch => f.write_str("etch"),
            LayerRole::Skip(why) => write!(f, "skip ({why})"),
        }
    }
}

/// One rule: a layer-name pattern and the role of the layers it matches.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LayerRule {
    /// Glob pattern (`*`, `?`), matched case-insensitively.
    pub pattern: String,
    /// The role.
    pub role: LayerRole,
}

impl FromStr for LayerRule {
    type Err = String;

    /// `PATTERN=ROLE`, ROLE one of `outside`, `inside`, `cut`, `etch`, `skip`.
    fn from_str(s: &str) -> Result<Self, String> {
        let (pattern, role) = s
            .rsplit_once('=')
            .ok_or_else(|| format!("{s:?}: expected PATTERN=ROLE, e.g. \"BEND*=skip\""))?;
        let role = match role.trim().to_ascii_lowercase().as_str() {
            "outside" => LayerRole::Outside,
            "inside" => LayerRole::Inside,
            "cut" => LayerRole::Cut,
            "etch" => LayerRole::Etch,
            "skip" => LayerRole::Skip("by a user rule".into()),
            other => {
                return Err(format!(
                    "{s:?}: role {other:?} is not one of outside, inside, cut, etch, skip"
                ))
            }
        };
        let pattern = pattern.trim();
        if pattern.is_empty() {
            return Err(format!("{s:?}: empty layer pattern"));
        }
        Ok(Self {
            pattern: pattern.to_string(),
            role,
        })
    }
}

/// The layer rules: `user` first, then [`LayerRules::defaults`]; unmatched layers cut.
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub struct LayerRules {
    /// The user's rules, tried before the defaults.
    pub user: Vec<LayerRule>,
}

/// The default rules: our shop layers, Autodesk Inventor's flat-pattern layers, and the
/// usual names of layers that hold no cut.
const DEFAULTS: &[(&str, &str)] = &[
    ("OUTSIDE", "outside"),
    ("IV_OUTER_PROFILE", "outside"),
    ("INSIDE", "inside"),
    ("IV_INTERIOR_PROFILES", "inside"),
    ("IV_FEATURE_PROFILES*", "inside"),
    ("ETCH", "etch"),
    ("MARK*", "etch"),
    ("SCRIBE*", "etch"),
    ("IV_MARK_SURFACE*", "etch"),
    ("INFO", "never cut (spinvalence information)"),
    ("DEFPOINTS", "never cut (dimension points)"),
    ("*BEND*", "bend lines"),
    ("IV_TANGENT", "bend lines"),
    ("IV_ROLL*", "bend lines"),
    ("*CONSTR*", "construction"),
    ("CENTER*", "construction"),
    ("*CENTRE*", "construction"),
    ("HIDDEN*", "construction"),
    ("IV_ARC_CENTERS", "construction"),
    ("IV_TOOL_CENTER*", "construction"),
    ("IV_ALTREP*", "construction"),
    ("IV_UNCONSUMED_SKETCHES", "construction"),
    ("DIM*", "dimensions and annotation"),
    ("*ANNO*", "dimensions and annotation"),
    ("NOTE*", "dimensions and annotation"),
    ("TEXT*", "dimensions and annotation"),
    ("BORDER*", "drawing border"),
    ("FRAME*", "drawing border"),
    ("TITLE*", "drawing border"),
];

impl LayerRules {
    /// The default rules as `(pattern, role)` text, for help and docs.
    pub fn defaults() -> impl Iterator<Item = (&'static str, &'static str)> {
        DEFAULTS.iter().copied()
    }

    /// The role of `layer`.
    pub fn role(&self, layer: &str) -> LayerRole {
        if let Some(r) = self.user.iter().find(|r| glob(&r.pattern, layer)) {
            return r.role.clone();
        }
        for &(pattern, role) in DEFAULTS {
            if glob(pattern, layer) {
                return match role {
                    "outside" => LayerRole::Outside,
                    "inside" => LayerRole::Inside,
                    "etch" => LayerRole::Etch,
                    why => LayerRole::Skip(why.to_string()),
                };
            }
        }
        LayerRole::Cut
    }
}

/// Case-insensitive glob match with `*` (any run) and `?` (one character).
fn glob(pattern: &str, name: &str) -> bool {
    let p: Vec<char> = pattern.to_uppercase().chars().collect();
    let s: Vec<char> = name.to_uppercase().chars().collect();
    let (mut i, mut j) = (0, 0);
    let (mut star, mut mark) = (None, 0);
    while j < s.len() {
        if i < p.len() && (p[i] == '?' || p[i] == s[j]) {
            i += 1;
            j += 1;
        } else if i < p.len() && p[i] == '*' {
            star = Some(i);
            mark = j;
            i += 1;
        } else if let Some(st) = star {
            i = st + 1;
            mark += 1;
            j = mark;
        } else {
            return false;
        }
    }
    while i < p.len() && p[i] == '*' {
        i += 1;
    }
    i == p.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_user_rules_and_globs() {
        let rules = LayerRules::default();
        assert_eq!(rules.role("outside"), LayerRole::Outside);
        assert_eq!(rules.role("0"), LayerRole::Cut);
        assert_eq!(rules.role("IV_INTERIOR_PROFILES"), LayerRole::Inside);
        assert!(matches!(rules.role("Bend_Lines"), LayerRole::Skip(w) if w == "bend lines"));
        assert!(matches!(rules.role("IV_BEND_DOWN"), LayerRole::Skip(_)));
        assert!(matches!(rules.role("Dimensions"), LayerRole::Skip(_)));
        assert_eq!(rules.role("Cutting"), LayerRole::Cut);
        let user = LayerRules {
            user: vec![
                "cut*=outside".parse().unwrap(),
                "DIM*=etch".parse().unwrap(),
            ],
        };
        assert_eq!(user.role("Cutting"), LayerRole::Outside);
        assert_eq!(user.role("dims"), LayerRole::Etch);
        assert!("BEND".parse::<LayerRule>().is_err());
        assert!("BEND=fold"
            .parse::<LayerRule>()
            .unwrap_err()
            .contains("fold"));
        assert!(glob("A?C*", "abcdef") && !glob("A?C", "abcd") && glob("*", ""));
    }
}
