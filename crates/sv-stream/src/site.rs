//! The site rules, without sockets: what a request does to the deployment and what it answers.
//!
//! - [`Plan`] is the frame as the streamer serves it (ids, strips, targets, links, the
//!   assembly sequence, tolerances): immutable, shared by every connection without a lock.
//!   It answers the requests that change nothing: `get_targets` pages, `track` checks,
//!   `overlap` checks.
//! - [`Ledger`] is the state of the deployment: completed units, claims, op ids, the site
//!   registration, the numbered events. [`Ledger::decide`] turns one request into a
//!   [`Decision`] without changing anything; the server stores the decision's event and only
//!   then calls [`Ledger::apply`] and broadcasts it (write before apply, `docs/protocol.md`).
//!
//! Time comes in as an argument (`now_ms`), so every rule is a pure function of its inputs.

use std::collections::{BTreeMap, HashMap};

use sv_frame::FrameFile;
use sv_geom::text::excerpt;
use sv_geom::{Isometry3, Point3};

use crate::geometry::{self, iso_of, kabsch, pose_of, transform_of, UnitTarget};
use crate::protocol::*;

/// Most events replayed on reconnect; a client further behind gets a snapshot.
pub const MAX_REPLAY: u64 = 10_000;

/// A refused request: the `error` code and message the client gets.
pub type Refusal = (ErrorCode, String);

/// Who sent a request.
#[derive(Clone, Copy, Debug)]
pub struct Who<'a> {
    /// Granted role.
    pub role: Role,
    /// The client id claims and completions are recorded under.
    pub client_id: &'a str,
}

/// What a ledger request does.
#[derive(Clone, Debug, PartialEq)]
pub enum Decision {
    /// Nothing changes: answer the requester.
    Reply(ServerMessage),
    /// Store `event`; once it is stored send `first` (if any) to the requester, apply and
    /// broadcast the event, then send `then` (if any) to the requester.
    Commit {
        /// Sent before the event (the `fit` of a registration).
        first: Option<Box<ServerMessage>>,
        /// The state change.
        event: Event,
        /// Sent after the event (the `ack`).
        then: Option<Box<ServerMessage>>,
    },
}

/// The frame as served: immutable after [`Plan::new`].
#[derive(Debug)]
pub struct Plan {
    ids: Vec<String>,
    strips: Vec<Option<String>>,
    targets: Vec<UnitTarget>,
    index: HashMap<String, usize>,
    overlaps: HashMap<(usize, usize), f64>,
    neighbours: Vec<Vec<usize>>,
    sequence: Vec<usize>,
    tolerance: Tolerance,
}

/// A validated `track`: the check to send and the measurement to record.
#[derive(Clone, Debug, PartialEq)]
pub struct Checked {
    /// The `check` answer.
    pub check: ServerMessage,
    /// The measurement row (pose, source and result) for the state file.
    pub record: serde_json::Value,
}

impl Plan {
    /// Read the frame: each face one unit with its own id ([`FrameFile::unit_problems`], as
    /// `spinvalence check` holds it), ids at most [`MAX_ID_LEN`] characters, targets, links.
    pub fn new(frame: &FrameFile, tolerance: Tolerance) -> Result<Plan, String> {
        if let Some(problem) = frame.unit_problems().first() {
            return Err(problem.to_string());
        }
        let ids = geometry::unit_ids(frame);
        let mut index = HashMap::new();
        for (i, id) in ids.iter().enumerate() {
            if id.chars().count() > MAX_ID_LEN {
                return Err(format!(
                    "unit {i} has an id longer than {MAX_ID_LEN} characters"
                ));
            }
            index.insert(id.clone(), i);
        }
        let targets = geometry::unit_targets(frame)?;
        let overlaps = geometry::design_overlaps(frame)?;
        let mut neighbours = vec![Vec::new(); ids.len()];
        for &(a, b) in overlaps.keys() {
            neighbours[a].push(b);
            neighbours[b].push(a);
        }
        for n in &mut neighbours {
            n.sort_unstable();
        }
        Ok(Plan {
            strips: geometry::unit_strips(frame),
            sequence: geometry::assembly_sequence(frame),
            ids,
            targets,
            index,
            overlaps,
            neighbours,
            tolerance,
        })
    }

    /// Units in the frame.
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// Never true ([`Plan::new`] refuses an empty frame).
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// The wire id of unit `u`.
    pub fn id(&self, u: usize) -> &str {
        &self.ids[u]
    }

    /// The tolerances checks are made with.
    pub fn tolerance(&self) -> Tolerance {
        self.tolerance
    }

    /// The index of a unit id, or `unknown_unit`.
    pub fn unit(&self, id: &str) -> Result<usize, Refusal> {
        self.index.get(id).copied().ok_or_else(|| {
            let shown = excerpt(id, QUOTED_CHARS);
            (ErrorCode::UnknownUnit, format!("no unit \"{shown}\""))
        })
    }

    /// Unit `u`'s target, in the site frame when `site` is given.
    pub fn target(&self, u: usize, site: Option<&Isometry3>) -> Target {
        let t = &self.targets[u];
        let map_pt = |p: &[f64; 3]| match site {
            Some(s) => {
                let q = s * Point3::new(p[0], p[1], p[2]);
                [q.x, q.y, q.z]
            }
            None => *p,
        };
        let map_pose = |iso: &Isometry3| match site {
            Some(s) => pose_of(&(s * iso)),
            None => pose_of(iso),
        };
        Target {
            id: self.ids[u].clone(),
            strip: self.strips[u].clone(),
            hub_pose: map_pose(&t.hub_pose),
            primary_pose: map_pose(&t.primary_pose),
            hub: t.hub.map(|p| map_pt(&p)),
            primary: t.primary.map(|p| map_pt(&p)),
            neighbours: self.neighbours[u]
                .iter()
                .map(|&v| self.ids[v].clone())
                .collect(),
        }
    }

    /// The `targets` page starting at unit `offset`: as many units as fit in
    /// [`MAX_PAGE_BYTES`] (at least one). `None` past the last unit.
    pub fn targets_page(
        &self,
        offset: usize,
        frame: CoordFrame,
        site: Option<&Isometry3>,
    ) -> Option<ServerMessage> {
        if offset >= self.len() {
            return None;
        }
        let applied = match frame {
            CoordFrame::Site => site,
            CoordFrame::Model => None,
        };
        // envelope with the longest offsets and totals, plus one comma per unit
        let mut bytes = 160;
        let mut units = Vec::new();
        for u in offset..self.len() {
            let t = self.target(u, applied);
            let len = to_text(&t).len() + 1;
            if !units.is_empty() && bytes + len > MAX_PAGE_BYTES {
                break;
            }
            bytes += len;
            units.push(t);
        }
        Some(ServerMessage::Targets {
            frame,
            registered: site.is_some(),
            offset,
            total: self.len(),
            units,
        })
    }

    /// Check a tracked pose against its target (the registration `site` applies to
    /// `frame: "site"` poses).
    #[allow(clippy::too_many_arguments)]
    pub fn check(
        &self,
        unit: &str,
        part: Part,
        pose: &Pose,
        source: Option<Source>,
        frame: CoordFrame,
        reference: Option<serde_json::Value>,
        coalesced: u64,
        site: Option<&Isometry3>,
    ) -> Result<Checked, Refusal> {
        let u = self.unit(unit)?;
        let tracked = iso_of(pose).ok_or((
            ErrorCode::BadMessage,
            "pose must be finite with a non-zero quaternion".to_string(),
        ))?;
        let t = &self.targets[u];
        let model = match part {
            Part::Hub => t.hub_pose,
            Part::Primary => t.primary_pose,
        };
        let target = match (frame, site) {
            (CoordFrame::Site, Some(s)) => s * model,
            _ => model,
        };
        let (position_error_mm, angle_error_deg, move_mm) = geometry::compare(&target, &tracked)
            .ok_or((
                ErrorCode::BadMessage,
                "pose too far out: the error is not a finite number".to_string(),
            ))?;
        let tol = &self.tolerance;
        let ok = position_error_mm <= tol.position_mm && angle_error_deg <= tol.angle_deg;
        let record = serde_json::json!({
            "part": part, "pose": pose, "source": source, "frame": frame, "ok": ok,
            "position_error_mm": position_error_mm, "angle_error_deg": angle_error_deg,
        });
        Ok(Checked {
            check: ServerMessage::Check {
                unit: unit.to_string(),
                part,
                ok,
                position_error_mm,
                angle_error_deg,
                move_mm,
                frame,
                coalesced,
                reference,
            },
            record,
        })
    }

    /// Compare a measured hub overlap with the design overlap of the link.
    pub fn overlap(&self, units: [String; 2], measured_mm: f64) -> Result<ServerMessage, Refusal> {
        let a = self.unit(&units[0])?;
        let b = self.unit(&units[1])?;
        if !measured_mm.is_finite() || measured_mm.abs() > 1e9 {
            return Err((
                ErrorCode::BadMessage,
                "measured_mm must be a finite length".into(),
            ));
        }
        let design_mm = *self.overlaps.get(&(a.min(b), a.max(b))).ok_or((
            ErrorCode::NotLinked,
            format!("{} and {} share no link", units[0], units[1]),
        ))?;
        let error_mm = measured_mm - design_mm;
        Ok(ServerMessage::OverlapCheck {
            units,
            design_mm,
            measured_mm,
            error_mm,
            ok: error_mm.abs() <= self.tolerance.overlap_mm,
        })
    }

    /// The first unit of the assembly sequence not done (other than `except`).
    fn next_after(&self, done: &[bool], except: Option<usize>) -> Option<String> {
        self.sequence
            .iter()
            .find(|&&v| !done[v] && Some(v) != except)
            .map(|&v| self.ids[v].clone())
    }
}

/// How one unit was completed (for `undo`).
#[derive(Clone, Debug)]
struct Completion {
    op_id: String,
    by: String,
    /// Server time of the completion; `None` when replayed from the state file.
    t_ms: Option<u64>,
}

/// The state of the deployment: rebuilt from the events, changed only by [`Ledger::apply`].
#[derive(Clone, Debug)]
pub struct Ledger {
    epoch: String,
    seq: u64,
    events: Vec<Event>,
    done: Vec<bool>,
    completed: Vec<usize>,
    ops: HashMap<String, usize>,
    undone: HashMap<String, usize>,
    claims: HashMap<usize, String>,
    completions: HashMap<usize, Completion>,
    registration: Option<Transform>,
    undo_window_ms: u64,
}

impl Ledger {
    /// An empty ledger of `units` units for the event stream `epoch`; a `complete` may be
    /// taken back for `undo_window_ms`.
    pub fn new(epoch: String, units: usize, undo_window_ms: u64) -> Ledger {
        Ledger {
            epoch,
            seq: 0,
            events: Vec::new(),
            done: vec![false; units],
            completed: Vec::new(),
            ops: HashMap::new(),
            undone: HashMap::new(),
            claims: HashMap::new(),
            completions: HashMap::new(),
            registration: None,
            undo_window_ms,
        }
    }

    /// The event stream's epoch.
    pub fn epoch(&self) -> &str {
        &self.epoch
    }

    /// The last event number.
    pub fn seq(&self) -> u64 {
        self.seq
    }

    /// The accepted site registration, as an isometry (`site = T model`).
    pub fn registration(&self) -> Option<Isometry3> {
        self.registration.as_ref().and_then(|t| {
            iso_of(&Pose {
                position: t.translation,
                rotation: t.rotation,
            })
        })
    }

    /// Units completed so far.
    pub fn done_count(&self) -> usize {
        self.completed.len()
    }

    /// Whether unit `u` is complete.
    pub fn is_done(&self, u: usize) -> bool {
        self.done[u]
    }

    /// Apply a stored event (live, or replayed from the state file with `now_ms: None`).
    pub fn apply(&mut self, plan: &Plan, event: &Event, now_ms: Option<u64>) {
        let unit = |id: &str| plan.index.get(id).copied();
        match event {
            Event::Progress {
                unit: id,
                op_id,
                by,
                ..
            } => {
                if let Some(u) = unit(id) {
                    if !self.done[u] {
                        self.done[u] = true;
                        self.completed.push(u);
                    }
                    self.ops.insert(op_id.clone(), u);
                    self.claims.remove(&u);
                    self.completions.insert(
                        u,
                        Completion {
                            op_id: op_id.clone(),
                            by: by.clone(),
                            t_ms: now_ms,
                        },
                    );
                }
            }
            Event::Reopened {
                unit: id, op_id, ..
            } => {
                if let Some(u) = unit(id) {
                    self.done[u] = false;
                    self.completed.retain(|&v| v != u);
                    self.completions.remove(&u);
                    self.undone.insert(op_id.clone(), u);
                }
            }
            Event::Claimed { unit: id, by, .. } => {
                if let Some(u) = unit(id) {
                    self.claims.insert(u, by.clone());
                }
            }
            Event::Released { unit: id, .. } => {
                if let Some(u) = unit(id) {
                    self.claims.remove(&u);
                }
            }
            Event::Registration { transform, .. } => self.registration = Some(*transform),
        }
        self.seq = event.seq();
        self.events.push(event.clone());
    }

    /// The whole state, for a `ready` in snapshot mode.
    pub fn snapshot(&self, plan: &Plan) -> Snapshot {
        Snapshot {
            completed: self
                .completed
                .iter()
                .map(|&u| plan.ids[u].clone())
                .collect(),
            claims: self
                .claims
                .iter()
                .map(|(&u, c)| (plan.ids[u].clone(), c.clone()))
                .collect::<BTreeMap<_, _>>(),
            done: self.completed.len(),
            total: plan.len(),
            next: plan.next_after(&self.done, None),
            registration: self.registration,
        }
    }

    /// The `ready` answer to a `hello` that saw `last`: the missed events when they are of
    /// this epoch, at most [`MAX_REPLAY`] and [`MAX_PAGE_BYTES`] of JSON; else a snapshot.
    pub fn ready(
        &self,
        plan: &Plan,
        role: Role,
        client_id: String,
        last: Option<&Cursor>,
    ) -> ServerMessage {
        let replay = last
            .filter(|c| {
                c.epoch == self.epoch && c.seq <= self.seq && self.seq - c.seq <= MAX_REPLAY
            })
            .map(|c| &self.events[c.seq as usize..])
            .filter(|events| {
                let mut bytes = 0;
                events.iter().all(|e| {
                    bytes += to_text(e).len() + 1;
                    bytes <= MAX_PAGE_BYTES
                })
            });
        let (mode, events, snapshot) = match replay {
            Some(events) => ("replay", Some(events.to_vec()), None),
            None => ("snapshot", None, Some(self.snapshot(plan))),
        };
        ServerMessage::Ready {
            role,
            client_id,
            epoch: self.epoch.clone(),
            seq: self.seq,
            mode: mode.into(),
            events,
            snapshot,
        }
    }

    /// What a ledger request (`claim`, `release`, `complete`, `undo`, `register`) does, at
    /// server time `now_ms`. Any other message is `Reply`-less: `None`.
    pub fn decide(
        &self,
        plan: &Plan,
        who: Who<'_>,
        msg: &ClientMessage,
        now_ms: u64,
    ) -> Option<Result<Decision, Refusal>> {
        let ledger_request = matches!(
            msg,
            ClientMessage::Claim { .. }
                | ClientMessage::Release { .. }
                | ClientMessage::Complete { .. }
                | ClientMessage::Undo { .. }
                | ClientMessage::Register { .. }
        );
        if !ledger_request {
            return None;
        }
        if who.role != Role::Operator {
            return Some(Err((
                ErrorCode::Forbidden,
                "viewers may only get_targets and ping".into(),
            )));
        }
        let by = who.client_id;
        Some(match msg {
            ClientMessage::Claim { unit } => self.claim(plan, by, unit, true),
            ClientMessage::Release { unit } => self.claim(plan, by, unit, false),
            ClientMessage::Complete { unit, op_id } => self.complete(plan, by, unit, op_id),
            ClientMessage::Undo { unit, op_id } => self.undo(plan, by, unit, op_id, now_ms),
            ClientMessage::Register { points } => self.register(plan, by, points),
            _ => unreachable!("not a ledger request"),
        })
    }

    fn ack(op: &str, unit: &str, applied: bool, seq: u64, op_id: Option<&str>) -> ServerMessage {
        ServerMessage::Ack {
            op: op.into(),
            unit: unit.into(),
            applied,
            seq,
            op_id: op_id.map(String::from),
        }
    }

    fn claim(&self, plan: &Plan, by: &str, unit: &str, take: bool) -> Result<Decision, Refusal> {
        let u = plan.unit(unit)?;
        if self.done[u] {
            return Err((
                ErrorCode::AlreadyDone,
                format!("{unit} is already complete"),
            ));
        }
        let op = if take { "claim" } else { "release" };
        let seq = self.seq + 1;
        let event = match (take, self.claims.get(&u)) {
            (true, Some(h)) if h == by => {
                return Ok(Decision::Reply(Self::ack(op, unit, false, self.seq, None)))
            }
            (true, Some(h)) => {
                return Err((ErrorCode::Claimed, format!("{unit} is claimed by {h}")))
            }
            (true, None) => Event::Claimed {
                seq,
                unit: unit.into(),
                by: by.into(),
            },
            (false, Some(h)) if h == by => Event::Released {
                seq,
                unit: unit.into(),
                by: by.into(),
            },
            (false, _) => {
                return Err((
                    ErrorCode::NotClaimed,
                    format!("{unit} is not claimed by you"),
                ))
            }
        };
        Ok(Decision::Commit {
            first: None,
            event,
            then: Some(Box::new(Self::ack(op, unit, true, seq, None))),
        })
    }

    fn complete(
        &self,
        plan: &Plan,
        by: &str,
        unit: &str,
        op_id: &str,
    ) -> Result<Decision, Refusal> {
        let u = plan.unit(unit)?;
        valid_op_id(op_id)?;
        match self.ops.get(op_id) {
            Some(&done) if done == u => {
                return Ok(Decision::Reply(Self::ack(
                    "complete",
                    unit,
                    false,
                    self.seq,
                    Some(op_id),
                )))
            }
            Some(&other) => {
                return Err((
                    ErrorCode::BadMessage,
                    format!("op_id already used for {}", plan.ids[other]),
                ))
            }
            None if self.done[u] => {
                return Err((
                    ErrorCode::AlreadyDone,
                    format!("{unit} is already complete"),
                ))
            }
            None => {}
        }
        if let Some(h) = self.claims.get(&u) {
            if h != by {
                return Err((ErrorCode::Claimed, format!("{unit} is claimed by {h}")));
            }
        }
        let seq = self.seq + 1;
        Ok(Decision::Commit {
            first: None,
            event: Event::Progress {
                seq,
                unit: unit.into(),
                by: by.into(),
                op_id: op_id.into(),
                done: self.completed.len() + 1,
                total: plan.len(),
                next: plan.next_after(&self.done, Some(u)),
            },
            then: Some(Box::new(Self::ack(
                "complete",
                unit,
                true,
                seq,
                Some(op_id),
            ))),
        })
    }

    fn undo(
        &self,
        plan: &Plan,
        by: &str,
        unit: &str,
        op_id: &str,
        now_ms: u64,
    ) -> Result<Decision, Refusal> {
        let u = plan.unit(unit)?;
        valid_op_id(op_id)?;
        if self.undone.get(op_id) == Some(&u) && !self.done[u] {
            return Ok(Decision::Reply(Self::ack(
                "undo",
                unit,
                false,
                self.seq,
                Some(op_id),
            )));
        }
        let refuse = |why: String| Err((ErrorCode::NotUndoable, why));
        let Some(c) = self.completions.get(&u) else {
            return refuse(format!("{unit} is not complete"));
        };
        if c.op_id != op_id {
            return refuse(format!("{unit} was not completed by op_id {op_id}"));
        }
        if c.by != by {
            return refuse(format!("{unit} was completed by {}, not by you", c.by));
        }
        match c.t_ms {
            Some(t) if now_ms.saturating_sub(t) <= self.undo_window_ms => {}
            _ => {
                return refuse(format!(
                    "the undo window of {} s for {unit} has passed",
                    self.undo_window_ms / 1000
                ))
            }
        }
        let mut done = self.done.clone();
        done[u] = false;
        let seq = self.seq + 1;
        Ok(Decision::Commit {
            first: None,
            event: Event::Reopened {
                seq,
                unit: unit.into(),
                by: by.into(),
                op_id: op_id.into(),
                done: self.completed.len() - 1,
                total: plan.len(),
                next: plan.next_after(&done, None),
            },
            then: Some(Box::new(Self::ack("undo", unit, true, seq, Some(op_id)))),
        })
    }

    fn register(
        &self,
        plan: &Plan,
        by: &str,
        points: &[[[f64; 3]; 2]],
    ) -> Result<Decision, Refusal> {
        if points.len() > MAX_REGISTER_POINTS {
            return Err((
                ErrorCode::BadMessage,
                format!("more than {MAX_REGISTER_POINTS} points"),
            ));
        }
        let fit = kabsch(points, geometry::DEFAULT_COLLINEAR_RATIO).map_err(|e| match e {
            geometry::FitError::Degenerate(m) => (ErrorCode::Degenerate, m),
        })?;
        let ok = fit.rms <= plan.tolerance.position_mm;
        let answer = ServerMessage::Fit {
            ok,
            transform: fit.transform(),
            residuals_mm: fit.residuals.clone(),
        };
        if !ok {
            return Ok(Decision::Reply(answer));
        }
        Ok(Decision::Commit {
            first: Some(Box::new(answer)),
            event: Event::Registration {
                seq: self.seq + 1,
                transform: transform_of(&fit.iso, fit.rms),
                by: by.into(),
            },
            then: None,
        })
    }
}

/// An id a client made (`client_id`, `op_id`): 1 to [`MAX_ID_LEN`] of `A-Za-z0-9-_.:`.
pub fn valid_id(s: &str) -> bool {
    !s.is_empty()
        && s.len() <= MAX_ID_LEN
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_.:".contains(c))
}

fn valid_op_id(op_id: &str) -> Result<(), Refusal> {
    if valid_id(op_id) {
        Ok(())
    } else {
        Err((
            ErrorCode::BadMessage,
            format!("op_id must be 1..={MAX_ID_LEN} of [A-Za-z0-9-_.:]"),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sv_frame::{solve, QuadMesh, SolveOptions};

    fn frame() -> FrameFile {
        let mesh = QuadMesh::sphere_cap(4, 4, 3000.0, 300.0);
        let solved = solve(&mesh, &SolveOptions::default(), &mut |_| {}).unwrap();
        let mut file = solved.to_frame_file(&mesh);
        for u in &mut file.units {
            u.strip = format!("S{}", u.face / 4);
        }
        file
    }

    /// The streamer refuses what `spinvalence check` fails: the one rule, asked of
    /// `FrameFile::unit_problems`.
    #[test]
    fn a_frame_without_one_unit_per_face_is_refused() {
        let t = Tolerance::default();
        assert!(Plan::new(&frame(), t).is_ok());
        let mut twice = frame();
        twice.units.push(twice.units[0].clone());
        let e = Plan::new(&twice, t).unwrap_err();
        assert!(e.starts_with("face 0 has 2 units"), "{e}");
        let mut lost = frame();
        lost.units.remove(3);
        assert_eq!(Plan::new(&lost, t).unwrap_err(), "face 3 has no unit");
        let mut none = frame();
        none.units.clear();
        assert_eq!(Plan::new(&none, t).unwrap_err(), "the frame has no units");
    }

    fn op(id: &str) -> Who<'_> {
        Who {
            role: Role::Operator,
            client_id: id,
        }
    }

    /// Decide and, for a commit, apply: the server's loop without the store and sockets.
    /// Returns the answers to the requester (the event itself is `ledger.events`' last).
    fn run(
        plan: &Plan,
        ledger: &mut Ledger,
        who: Who<'_>,
        msg: ClientMessage,
        now: u64,
    ) -> Result<Vec<ServerMessage>, ErrorCode> {
        match ledger
            .decide(plan, who, &msg, now)
            .expect("a ledger request")
        {
            Err((code, _)) => Err(code),
            Ok(Decision::Reply(m)) => Ok(vec![m]),
            Ok(Decision::Commit { first, event, then }) => {
                assert_eq!(
                    event.seq(),
                    ledger.seq() + 1,
                    "events are numbered in order"
                );
                ledger.apply(plan, &event, Some(now));
                Ok(first.into_iter().chain(then).map(|m| *m).collect())
            }
        }
    }

    fn complete(unit: &str, op_id: &str) -> ClientMessage {
        ClientMessage::Complete {
            unit: unit.into(),
            op_id: op_id.into(),
        }
    }

    #[test]
    fn claims_belong_to_one_client() {
        let f = frame();
        let plan = Plan::new(&f, Tolerance::default()).unwrap();
        let mut l = Ledger::new("e".into(), plan.len(), 10_000);
        let u = plan.id(3).to_string();
        let claim = ClientMessage::Claim { unit: u.clone() };
        assert!(run(&plan, &mut l, op("a"), claim.clone(), 0).is_ok());
        assert_eq!(l.seq(), 1);
        assert_eq!(
            run(&plan, &mut l, op("b"), claim.clone(), 0),
            Err(ErrorCode::Claimed)
        );
        assert_eq!(
            run(&plan, &mut l, op("b"), complete(&u, "b-1"), 0),
            Err(ErrorCode::Claimed)
        );
        let again = run(&plan, &mut l, op("a"), claim, 0).unwrap();
        assert!(matches!(
            &again[..],
            [ServerMessage::Ack {
                applied: false,
                seq: 1,
                ..
            }]
        ));
        let release = ClientMessage::Release { unit: u.clone() };
        assert_eq!(
            run(&plan, &mut l, op("b"), release.clone(), 0),
            Err(ErrorCode::NotClaimed)
        );
        assert!(run(&plan, &mut l, op("a"), release, 0).is_ok());
        assert!(run(&plan, &mut l, op("b"), complete(&u, "b-1"), 0).is_ok());
        let viewer = Who {
            role: Role::Viewer,
            client_id: "v",
        };
        assert_eq!(
            run(&plan, &mut l, viewer, complete(plan.id(0), "v-1"), 0),
            Err(ErrorCode::Forbidden)
        );
        let ping = ClientMessage::Ping { t: None };
        assert!(l.decide(&plan, op("a"), &ping, 0).is_none());
    }

    #[test]
    fn a_complete_applies_once_and_reports_the_next_unit() {
        let f = frame();
        let plan = Plan::new(&f, Tolerance::default()).unwrap();
        let mut l = Ledger::new("e".into(), plan.len(), 10_000);
        let first = l.snapshot(&plan).next.unwrap();
        let out = run(&plan, &mut l, op("a"), complete(&first, "op-1"), 0).unwrap();
        let ServerMessage::Ack { applied, seq, .. } = out[0] else {
            panic!("{out:?}")
        };
        assert!(applied);
        assert_eq!(seq, 1);
        let Some(Event::Progress { done, next, .. }) = l.events.last().cloned() else {
            panic!()
        };
        assert_eq!(done, 1);
        assert_ne!(next.as_deref(), Some(first.as_str()));
        assert_eq!(l.snapshot(&plan).next, next);
        // a retry with the same op_id changes nothing
        let retry = run(&plan, &mut l, op("a"), complete(&first, "op-1"), 0).unwrap();
        assert!(matches!(
            &retry[..],
            [ServerMessage::Ack {
                applied: false,
                seq: 1,
                ..
            }]
        ));
        assert_eq!(l.seq(), 1);
        assert_eq!(
            run(&plan, &mut l, op("a"), complete(&first, "op-2"), 0),
            Err(ErrorCode::AlreadyDone)
        );
        assert_eq!(
            run(&plan, &mut l, op("a"), complete(plan.id(5), "op-1"), 0),
            Err(ErrorCode::BadMessage)
        );
        assert_eq!(
            run(&plan, &mut l, op("a"), complete(plan.id(5), "bad op"), 0),
            Err(ErrorCode::BadMessage)
        );
    }

    #[test]
    fn undo_takes_back_a_complete_within_the_window() {
        let f = frame();
        let plan = Plan::new(&f, Tolerance::default()).unwrap();
        let mut l = Ledger::new("e".into(), plan.len(), 10_000);
        let u = l.snapshot(&plan).next.unwrap();
        let undo = |op_id: &str| ClientMessage::Undo {
            unit: u.clone(),
            op_id: op_id.into(),
        };
        assert_eq!(
            run(&plan, &mut l, op("a"), undo("op-1"), 0),
            Err(ErrorCode::NotUndoable)
        );
        run(&plan, &mut l, op("a"), complete(&u, "op-1"), 1_000).unwrap();
        assert_eq!(
            run(&plan, &mut l, op("b"), undo("op-1"), 2_000),
            Err(ErrorCode::NotUndoable),
            "only the welder who completed it"
        );
        assert_eq!(
            run(&plan, &mut l, op("a"), undo("op-9"), 2_000),
            Err(ErrorCode::NotUndoable)
        );
        run(&plan, &mut l, op("a"), undo("op-1"), 11_000).unwrap();
        assert!(!l.is_done(plan.unit(&u).unwrap()));
        assert_eq!(l.done_count(), 0);
        assert_eq!(l.snapshot(&plan).next.as_deref(), Some(u.as_str()));
        // a retried undo is harmless; the spent op_id does not complete the unit again
        let again = run(&plan, &mut l, op("a"), undo("op-1"), 11_000).unwrap();
        assert!(matches!(
            &again[..],
            [ServerMessage::Ack { applied: false, .. }]
        ));
        let replayed = run(&plan, &mut l, op("a"), complete(&u, "op-1"), 11_000).unwrap();
        assert!(matches!(
            &replayed[..],
            [ServerMessage::Ack { applied: false, .. }]
        ));
        assert!(!l.is_done(plan.unit(&u).unwrap()));
        // a new complete, then too late to undo
        run(&plan, &mut l, op("a"), complete(&u, "op-2"), 20_000).unwrap();
        assert_eq!(
            run(
                &plan,
                &mut l,
                op("a"),
                ClientMessage::Undo {
                    unit: u.clone(),
                    op_id: "op-2".into()
                },
                30_001
            ),
            Err(ErrorCode::NotUndoable)
        );
        // a ledger rebuilt from the events agrees, and cannot undo replayed completions
        let mut rebuilt = Ledger::new("e".into(), plan.len(), 10_000);
        for e in &l.events {
            rebuilt.apply(&plan, e, None);
        }
        assert_eq!(rebuilt.snapshot(&plan), l.snapshot(&plan));
        assert_eq!(
            run(
                &plan,
                &mut rebuilt,
                op("a"),
                ClientMessage::Undo {
                    unit: u.clone(),
                    op_id: "op-2".into()
                },
                20_001
            ),
            Err(ErrorCode::NotUndoable)
        );
    }

    #[test]
    fn registration_is_refused_above_tolerance_and_stored_below() {
        let f = frame();
        let plan = Plan::new(&f, Tolerance::default()).unwrap();
        let mut l = Ledger::new("e".into(), plan.len(), 10_000);
        let shift = |p: [f64; 3], e: f64| [p[0] + 100.0 + e, p[1] - 50.0, p[2] + 7.0];
        let pts = |noise: f64| -> Vec<[[f64; 3]; 2]> {
            [0usize, 3, 12, 15]
                .iter()
                .enumerate()
                .map(|(k, &u)| {
                    let m = f.units[u].hub[0];
                    [m, shift(m, if k % 2 == 0 { noise } else { -noise })]
                })
                .collect()
        };
        let noisy = ClientMessage::Register { points: pts(30.0) };
        let out = run(&plan, &mut l, op("s"), noisy, 0).unwrap();
        assert!(matches!(&out[..], [ServerMessage::Fit { ok: false, .. }]));
        assert!(l.registration().is_none());
        let good = ClientMessage::Register { points: pts(0.0) };
        let out = run(&plan, &mut l, op("s"), good, 0).unwrap();
        assert!(matches!(&out[0], ServerMessage::Fit { ok: true, .. }));
        let t = l.registration().unwrap().translation.vector;
        assert!(
            (t.x - 100.0).abs() < 1e-6 && (t.y + 50.0).abs() < 1e-6,
            "{t}"
        );
        let huge = ClientMessage::Register {
            points: vec![
                [[0.0; 3], [1e308; 3]],
                [[1000.0, 0.0, 0.0], [-1e308, 1e308, 0.0]],
                [[0.0, 1000.0, 0.0], [1e308, -1e308, 1e308]],
            ],
        };
        assert_eq!(
            run(&plan, &mut l, op("s"), huge, 0),
            Err(ErrorCode::Degenerate)
        );
    }

    #[test]
    fn checks_and_pages() {
        let f = frame();
        let plan = Plan::new(&f, Tolerance::default()).unwrap();
        let target = pose_of(&geometry::tile_pose(&f.units[2].hub).unwrap());
        let c = plan
            .check(
                plan.id(2),
                Part::Hub,
                &target,
                None,
                CoordFrame::Site,
                None,
                0,
                None,
            )
            .unwrap();
        assert!(matches!(c.check, ServerMessage::Check { ok: true, .. }));
        let mut off = target;
        off.position[0] += 5.01;
        let c = plan
            .check(
                plan.id(2),
                Part::Hub,
                &off,
                None,
                CoordFrame::Site,
                None,
                0,
                None,
            )
            .unwrap();
        assert!(matches!(c.check, ServerMessage::Check { ok: false, .. }));
        off.position[0] -= 0.02;
        let c = plan
            .check(
                plan.id(2),
                Part::Hub,
                &off,
                None,
                CoordFrame::Site,
                None,
                0,
                None,
            )
            .unwrap();
        assert!(matches!(c.check, ServerMessage::Check { ok: true, .. }));
        let far = Pose {
            position: [f64::MAX, -f64::MAX, 0.0],
            rotation: [0.0, 0.0, 0.0, 1.0],
        };
        let site = Isometry3::translation(-f64::MAX, f64::MAX, 0.0);
        let e = plan
            .check(
                plan.id(2),
                Part::Hub,
                &far,
                None,
                CoordFrame::Site,
                None,
                0,
                Some(&site),
            )
            .unwrap_err();
        assert_eq!(e.0, ErrorCode::BadMessage);
        // every unit comes in exactly one page, in order
        let Some(ServerMessage::Targets { units, total, .. }) =
            plan.targets_page(0, CoordFrame::Model, None)
        else {
            panic!()
        };
        assert_eq!((units.len(), total), (16, 16));
        assert!(units.iter().all(|u| !u.neighbours.is_empty()));
        assert!(plan.targets_page(16, CoordFrame::Model, None).is_none());
    }
}
