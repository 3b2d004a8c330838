//! Protocol v1 wire types (external form: mm, degrees, quaternions `[x, y, z, w]`).
//!
//! Every message is one JSON text frame with a `"type"` tag. Client messages are
//! [`ClientMessage`]; the server answers with [`ServerMessage`] (to one client) or broadcasts an
//! [`Event`] (numbered by `seq`, persisted, replayed on reconnect). `docs/protocol.md` and
//! `schema/*.json` describe the same shapes; within v1 only additions are allowed.

use serde::{Deserialize, Serialize};
use serde_json::Value;
use sv_geom::text::excerpt;

/// The protocol version announced in `welcome`.
pub const PROTOCOL_VERSION: u32 = 1;
/// The websocket subprotocol a client must offer.
pub const SUBPROTOCOL: &str = "spinvalence.v1";
/// Largest text message the server handles (bytes); larger ones get `error` `too_large`.
pub const MAX_MESSAGE_BYTES: usize = 64 * 1024;
/// Websocket transport limit (frame and message, bytes); beyond it the connection closes (1009).
pub const MAX_TRANSPORT_BYTES: usize = 128 * 1024;
/// Longest accepted identifier (`client_id`, `op_id`, unit ids in requests).
pub const MAX_ID_LEN: usize = 128;
/// Most registration point pairs in one `register`.
pub const MAX_REGISTER_POINTS: usize = 1000;

/// Close code: no `hello` in time.
pub const CLOSE_HELLO_TIMEOUT: u16 = 4408;
/// Close code: bad token.
pub const CLOSE_UNAUTHORIZED: u16 = 4401;
/// Close code: too many wrong tokens from this address; retry later.
pub const CLOSE_THROTTLED: u16 = 4429;
/// Largest `targets` page and largest replay carried by `ready` (bytes of JSON); a larger
/// frame comes in several `targets` pages, a longer replay as a snapshot.
pub const MAX_PAGE_BYTES: usize = 256 * 1024;
/// Shortest accepted `--token` / `--viewer-token`: a shorter one falls to guessing.
pub const MIN_TOKEN_LEN: usize = 12;

/// A rigid pose: position (mm) and rotation as a unit quaternion `[x, y, z, w]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Origin (mm).
    pub position: [f64; 3],
    /// Unit quaternion `[x, y, z, w]`.
    pub rotation: [f64; 4],
}

/// Acceptance tolerances, sent in `welcome`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Tolerance {
    /// Largest position error (mm) of an accepted part and largest registration RMS.
    pub position_mm: f64,
    /// Largest rotation error (degrees) of an accepted part.
    pub angle_deg: f64,
    /// Largest difference (mm) between measured and design hub overlap.
    pub overlap_mm: f64,
}

impl Tolerance {
    /// AR tracking is good to a few mm at best, so 5 mm is the sane default.
    pub const DEFAULT_POSITION_MM: f64 = 5.0;
    /// Default rotation tolerance (degrees).
    pub const DEFAULT_ANGLE_DEG: f64 = 1.0;
    /// Default overlap tolerance (mm), a tape or caliper reading.
    pub const DEFAULT_OVERLAP_MM: f64 = 2.0;
}

impl Default for Tolerance {
    fn default() -> Self {
        Self {
            position_mm: Self::DEFAULT_POSITION_MM,
            angle_deg: Self::DEFAULT_ANGLE_DEG,
            overlap_mm: Self::DEFAULT_OVERLAP_MM,
        }
    }
}

/// Which part of a unit a pose belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Part {
    /// The hub (secondary tile).
    Hub,
    /// The primary tile.
    Primary,
}

/// Coordinates of poses in a request or answer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CoordFrame {
    /// Site coordinates: the registration applied (the model frame until one is accepted).
    #[default]
    Site,
    /// Model (design) coordinates, as in `frame.json`.
    Model,
}

/// Where a tracked pose came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Source {
    /// QR code marker.
    Qr,
    /// ArUco marker.
    Aruco,
    /// Typed in.
    Manual,
    /// Simulated tracker.
    Sim,
    /// Measured in the AR page: hub corners picked with a controller, a hand ray or a screen
    /// tap (hit-test), the pose fitted to them.
    Ar,
}

/// What a connection may do.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    /// Read-only: `get_targets`, `ping`.
    Viewer,
    /// Everything.
    Operator,
}

/// Position in the event stream a client has seen.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Cursor {
    /// The epoch the client saw.
    pub epoch: String,
    /// The last event `seq` it applied.
    pub seq: u64,
}

/// A message from a client.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ClientMessage {
    /// First message, within the hello timeout.
    Hello {
        /// Operator or viewer token (empty when the server has none).
        #[serde(default)]
        token: String,
        /// Stable device id (claims belong to it); generated when absent.
        #[serde(default)]
        client_id: Option<String>,
        /// What the client already has, for replay.
        #[serde(default)]
        last: Option<Cursor>,
    },
    /// Ask for all target poses.
    GetTargets {
        /// Coordinates of the answer.
        #[serde(default)]
        frame: CoordFrame,
    },
    /// A tracked pose of one part.
    Track {
        /// Unit id.
        unit: String,
        /// Which part.
        part: Part,
        /// The tracked pose.
        pose: Pose,
        /// Tracker kind.
        #[serde(default)]
        source: Option<Source>,
        /// Coordinates of `pose` (and of the answer).
        #[serde(default)]
        frame: CoordFrame,
        /// Echoed in `check`.
        #[serde(default, rename = "ref")]
        reference: Option<Value>,
    },
    /// A measured hub overlap between two linked units.
    Overlap {
        /// The two unit ids.
        units: [String; 2],
        /// Measured overlap (mm).
        measured_mm: f64,
    },
    /// Take a unit.
    Claim {
        /// Unit id.
        unit: String,
    },
    /// Give a unit back.
    Release {
        /// Unit id.
        unit: String,
    },
    /// The unit is deployed and welded.
    Complete {
        /// Unit id.
        unit: String,
        /// Idempotency key (a UUID); applied once.
        op_id: String,
    },
    /// Take back a `complete` within the undo window (same client, same `op_id`).
    Undo {
        /// Unit id.
        unit: String,
        /// The `op_id` of the `complete` to take back.
        op_id: String,
    },
    /// Site registration: pairs `[model xyz, measured xyz]`.
    Register {
        /// At least 3 non-collinear pairs.
        points: Vec<[[f64; 3]; 2]>,
    },
    /// Application-level ping.
    Ping {
        /// Echoed in `pong`.
        #[serde(default)]
        t: Option<Value>,
    },
}

/// Every `type` a client may send.
pub const CLIENT_TYPES: [&str; 10] = [
    "hello",
    "get_targets",
    "track",
    "overlap",
    "claim",
    "release",
    "complete",
    "undo",
    "register",
    "ping",
];

/// `welcome.frame`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameInfo {
    /// Number of units.
    pub units: usize,
    /// Always `"mm"`.
    pub length_unit: String,
    /// Always `"+Z"`.
    pub up: String,
    /// Always `"xyzw"`.
    pub quaternion: String,
}

/// One unit's targets.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Target {
    /// Unit id.
    pub id: String,
    /// Strip label (`null` when the frame has none).
    pub strip: Option<String>,
    /// Hub tile pose.
    pub hub_pose: Pose,
    /// Primary tile pose.
    pub primary_pose: Pose,
    /// Hub corners.
    pub hub: [[f64; 3]; 4],
    /// Primary corners.
    pub primary: [[f64; 3]; 4],
    /// Ids of the units sharing a link with this one (an `overlap` is measured with them).
    pub neighbours: Vec<String>,
}

/// The state a client missed, when replay is not possible.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Snapshot {
    /// Completed unit ids, in completion order.
    pub completed: Vec<String>,
    /// Claimed unit id -> client id.
    pub claims: std::collections::BTreeMap<String, String>,
    /// Units completed.
    pub done: usize,
    /// Units in the frame.
    pub total: usize,
    /// Next unit in the assembly sequence.
    pub next: Option<String>,
    /// The accepted registration, if any.
    pub registration: Option<Transform>,
}

/// A rigid transform `site = R model + t`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Transform {
    /// `R` as a quaternion `[x, y, z, w]`.
    pub rotation: [f64; 4],
    /// `t` (mm).
    pub translation: [f64; 3],
    /// RMS residual of the fit (mm).
    pub rms_mm: f64,
}

/// A message from the server to one client.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ServerMessage {
    /// First message on every connection.
    Welcome {
        /// [`PROTOCOL_VERSION`].
        protocol: u32,
        /// Identifies the event stream (the state file).
        epoch: String,
        /// Last event `seq`.
        seq: u64,
        /// Websocket ping interval (ms).
        heartbeat_ms: u64,
        /// Frame summary.
        frame: FrameInfo,
        /// Acceptance tolerances.
        tolerance: Tolerance,
    },
    /// Answer to `hello`.
    Ready {
        /// Granted role.
        role: Role,
        /// The client id claims are recorded under.
        client_id: String,
        /// Current epoch.
        epoch: String,
        /// Current `seq`.
        seq: u64,
        /// `"replay"` or `"snapshot"`.
        mode: String,
        /// Missed events (replay mode).
        #[serde(skip_serializing_if = "Option::is_none")]
        events: Option<Vec<Event>>,
        /// Whole state (snapshot mode).
        #[serde(skip_serializing_if = "Option::is_none")]
        snapshot: Option<Snapshot>,
    },
    /// Answer to `get_targets`.
    Targets {
        /// Coordinates of the poses.
        frame: CoordFrame,
        /// Whether a registration is applied.
        registered: bool,
        /// Index of this page's first unit in the frame (pages come in order).
        offset: usize,
        /// Units in the frame: the answer is complete when `offset + units.len() == total`.
        total: usize,
        /// This page's units, in file order (at most [`MAX_PAGE_BYTES`] of JSON per page).
        units: Vec<Target>,
    },
    /// Answer to `track`.
    Check {
        /// Unit id.
        unit: String,
        /// Part.
        part: Part,
        /// Within tolerance.
        ok: bool,
        /// Distance between target and tracked origin (mm).
        position_error_mm: f64,
        /// Rotation angle between target and tracked pose (degrees).
        angle_error_deg: f64,
        /// Target minus tracked position (mm), in `frame`.
        move_mm: [f64; 3],
        /// Coordinates of `move_mm`.
        frame: CoordFrame,
        /// `track` messages for this unit and part that the rate limit replaced by a later
        /// one since the previous `check` (latest wins); sent tracks = checks + coalesced.
        coalesced: u64,
        /// Echo of `track.ref`.
        #[serde(rename = "ref", skip_serializing_if = "Option::is_none")]
        reference: Option<Value>,
    },
    /// Answer to `overlap`.
    OverlapCheck {
        /// The two unit ids.
        units: [String; 2],
        /// Design overlap (mm) from the frame's link.
        design_mm: f64,
        /// Measured overlap (mm).
        measured_mm: f64,
        /// `measured - design` (mm).
        error_mm: f64,
        /// Within tolerance.
        ok: bool,
    },
    /// Answer to `claim`, `release`, `complete`.
    Ack {
        /// `"claim"`, `"release"` or `"complete"`.
        op: String,
        /// Unit id.
        unit: String,
        /// False when nothing changed (already held, op_id seen before).
        applied: bool,
        /// Current `seq` after the operation.
        seq: u64,
        /// Echo of `complete.op_id`.
        #[serde(skip_serializing_if = "Option::is_none")]
        op_id: Option<String>,
    },
    /// Answer to `register`.
    Fit {
        /// Accepted and applied.
        ok: bool,
        /// The fitted transform.
        transform: Transform,
        /// Per-point residual (mm), in request order.
        residuals_mm: Vec<f64>,
    },
    /// Answer to `ping`.
    Pong {
        /// Echo.
        #[serde(skip_serializing_if = "Option::is_none")]
        t: Option<Value>,
        /// Server time (ms since the Unix epoch).
        server_ms: u64,
    },
    /// A request failed; the connection stays open.
    Error {
        /// Machine-readable code.
        code: ErrorCode,
        /// Human-readable message.
        message: String,
    },
}

/// `error.code`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ErrorCode {
    /// Not JSON, or a field is wrong.
    BadMessage,
    /// `type` missing or unknown.
    UnknownType,
    /// Larger than [`MAX_MESSAGE_BYTES`].
    TooLarge,
    /// Bad token (the connection then closes with 4401).
    Unauthorized,
    /// Anything but `hello` before `ready`, or `hello` twice.
    NotReady,
    /// Not allowed for this role.
    Forbidden,
    /// No such unit.
    UnknownUnit,
    /// The two units share no link.
    NotLinked,
    /// Claimed by another client.
    Claimed,
    /// Already completed.
    AlreadyDone,
    /// Release of a unit this client does not hold.
    NotClaimed,
    /// Registration points collinear or too few.
    Degenerate,
    /// `undo` of a complete that is not this client's, not the unit's last, or too old.
    NotUndoable,
    /// Too many wrong tokens from this address (then close 4429).
    Throttled,
    /// Server fault (persistence).
    Internal,
}

/// A numbered state change, broadcast to every ready client, stored and replayed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Event {
    /// A unit was completed.
    Progress {
        /// Event number.
        seq: u64,
        /// Completed unit.
        unit: String,
        /// Client id that completed it.
        by: String,
        /// The operation id.
        op_id: String,
        /// Units completed.
        done: usize,
        /// Units in the frame.
        total: usize,
        /// Next unit in the assembly sequence (none when all are done).
        next: Option<String>,
    },
    /// A unit was claimed.
    Claimed {
        /// Event number.
        seq: u64,
        /// Unit id.
        unit: String,
        /// Client id.
        by: String,
    },
    /// A unit was released.
    Released {
        /// Event number.
        seq: u64,
        /// Unit id.
        unit: String,
        /// Client id.
        by: String,
    },
    /// A completed unit was taken back (`undo`).
    Reopened {
        /// Event number.
        seq: u64,
        /// The unit, no longer complete.
        unit: String,
        /// Client id that took it back.
        by: String,
        /// The `op_id` of the undone `complete`.
        op_id: String,
        /// Units completed.
        done: usize,
        /// Units in the frame.
        total: usize,
        /// Next unit in the assembly sequence.
        next: Option<String>,
    },
    /// A registration was accepted.
    Registration {
        /// Event number.
        seq: u64,
        /// The applied transform.
        transform: Transform,
        /// Client id.
        by: String,
    },
}

impl Event {
    /// The event number.
    pub fn seq(&self) -> u64 {
        match self {
            Event::Progress { seq, .. }
            | Event::Claimed { seq, .. }
            | Event::Released { seq, .. }
            | Event::Reopened { seq, .. }
            | Event::Registration { seq, .. } => *seq,
        }
    }
}

/// Serialise a message (infallible for these types).
pub fn to_text<T: Serialize>(message: &T) -> String {
    serde_json::to_string(message).unwrap_or_else(|e| {
        format!(r#"{{"type":"error","code":"internal","message":"serialise: {e}"}}"#)
    })
}

/// Longest field error quoted in a `bad_message` (characters, before escaping): serde's
/// message quotes the client's text (an unknown key or variant) as it came, line breaks and
/// all, so its control characters are escaped and a long one loses its middle.
const FIELD_ERROR_CHARS: usize = 160;

/// Characters of a client's type or unit id quoted in an error (the middle cut out beyond).
pub(crate) const QUOTED_CHARS: usize = 40;

/// Parse a client message, telling unknown types from bad fields.
pub fn parse_client(text: &str) -> Result<ClientMessage, (ErrorCode, String)> {
    if text.len() > MAX_MESSAGE_BYTES {
        return Err((
            ErrorCode::TooLarge,
            format!("message of {} bytes > {MAX_MESSAGE_BYTES}", text.len()),
        ));
    }
    let value: Value = serde_json::from_str(text)
        .map_err(|e| (ErrorCode::BadMessage, format!("not JSON: {e}")))?;
    let kind = value
        .get("type")
        .and_then(Value::as_str)
        .ok_or((ErrorCode::UnknownType, "missing \"type\"".to_string()))?
        .to_string();
    if !CLIENT_TYPES.contains(&kind.as_str()) {
        let shown = excerpt(&kind, QUOTED_CHARS);
        return Err((ErrorCode::UnknownType, format!("unknown type \"{shown}\"")));
    }
    serde_json::from_value(value).map_err(|e| {
        let why = excerpt(&e.to_string(), FIELD_ERROR_CHARS);
        (ErrorCode::BadMessage, format!("{kind}: {why}"))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_kinds() {
        assert!(matches!(
            parse_client(r#"{"type":"ping"}"#),
            Ok(ClientMessage::Ping { t: None })
        ));
        assert_eq!(parse_client("{").unwrap_err().0, ErrorCode::BadMessage);
        assert_eq!(
            parse_client(r#"{"type":"dance"}"#).unwrap_err().0,
            ErrorCode::UnknownType
        );
        assert_eq!(
            parse_client(r#"{"type":"claim"}"#).unwrap_err().0,
            ErrorCode::BadMessage
        );
        let big = format!(r#"{{"type":"ping","t":"{}"}}"#, "x".repeat(70_000));
        assert_eq!(parse_client(&big).unwrap_err().0, ErrorCode::TooLarge);
    }
}
