//! SQLite persistence (rusqlite, bundled).
//!
//! The `events` table is the source of truth: every numbered [`Event`] is written (with the
//! derived `completed` / `claims` / `registration` rows, for people reading the file) in one
//! transaction, and the write-ahead log is fsynced, before the event is applied, broadcast or
//! acknowledged. Measurements (`track`, `overlap`) go to `measurements` through a writer
//! thread that batches them; a measurement that cannot be written is counted and reported to
//! the client that sent it. `meta` holds the epoch and the frame hash.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{mpsc, Arc};
use std::thread::JoinHandle;

use rusqlite::{params, Connection, OptionalExtension};

use crate::protocol::Event;
use crate::StreamError;

const SCHEMA: &str = "
PRAGMA journal_mode = WAL;
PRAGMA synchronous = NORMAL; -- plus an fsync of the log after every event (Store::sync)
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS events (seq INTEGER PRIMARY KEY, kind TEXT NOT NULL, json TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS completed (unit TEXT PRIMARY KEY, op_id TEXT NOT NULL UNIQUE,
    client_id TEXT NOT NULL, seq INTEGER NOT NULL);
CREATE TABLE IF NOT EXISTS claims (unit TEXT PRIMARY KEY, client_id TEXT NOT NULL, seq INTEGER NOT NULL);
CREATE TABLE IF NOT EXISTS registration (id INTEGER PRIMARY KEY CHECK (id = 1), json TEXT NOT NULL,
    seq INTEGER NOT NULL);
CREATE TABLE IF NOT EXISTS measurements (id INTEGER PRIMARY KEY, t_ms INTEGER NOT NULL,
    client_id TEXT NOT NULL, kind TEXT NOT NULL, unit TEXT NOT NULL, json TEXT NOT NULL);
";

/// The event store.
pub(crate) struct Store {
    conn: Connection,
    /// The write-ahead log, fsynced after every commit (`None` in memory).
    wal: Option<PathBuf>,
    /// fsyncs of the log that succeeded: the test hook behind [`crate::Stats::event_fsyncs`].
    pub fsyncs: Arc<AtomicU64>,
}

fn db(e: rusqlite::Error) -> StreamError {
    StreamError::State(e.to_string())
}

/// What a store held when opened.
pub(crate) struct Loaded {
    pub epoch: String,
    pub events: Vec<Event>,
}

impl Store {
    /// Open (or create) the state file; `None` keeps everything in memory. `max_pages`
    /// caps the file (SQLite's `max_page_count`), for tests of a full disk.
    pub fn open(
        path: Option<&Path>,
        frame_hash: &str,
        max_pages: Option<u64>,
    ) -> Result<(Store, Loaded), StreamError> {
        let conn = match path {
            Some(p) => Connection::open(p).map_err(db)?,
            None => Connection::open_in_memory().map_err(db)?,
        };
        conn.busy_timeout(std::time::Duration::from_secs(5))
            .map_err(db)?;
        conn.execute_batch(SCHEMA).map_err(db)?;
        let get = |k: &str| -> Result<Option<String>, StreamError> {
            conn.query_row("SELECT value FROM meta WHERE key = ?1", [k], |r| r.get(0))
                .optional()
                .map_err(db)
        };
        let epoch = match (get("epoch")?, get("frame_hash")?) {
            (Some(e), Some(h)) if h == frame_hash => e,
            (Some(_), Some(h)) => {
                return Err(StreamError::State(format!(
                    "state file belongs to another frame (hash {h}, this frame {frame_hash}); \
                     use a new --state file"
                )))
            }
            _ => {
                let e = new_epoch();
                conn.execute(
                    "INSERT OR REPLACE INTO meta (key, value) VALUES ('epoch', ?1), ('frame_hash', ?2)",
                    params![e, frame_hash],
                )
                .map_err(db)?;
                e
            }
        };
        let mut events = Vec::new();
        {
            let mut stmt = conn
                .prepare("SELECT json FROM events ORDER BY seq")
                .map_err(db)?;
            let rows = stmt.query_map([], |r| r.get::<_, String>(0)).map_err(db)?;
            for row in rows {
                let text = row.map_err(db)?;
                let ev: Event = serde_json::from_str(&text)
                    .map_err(|e| StreamError::State(format!("bad event row: {e}")))?;
                events.push(ev);
            }
        }
        if let Some(pages) = max_pages {
            conn.pragma_update(None, "max_page_count", pages as i64)
                .map_err(db)?;
        }
        let wal = path.map(|p| {
            let mut name = p.as_os_str().to_owned();
            name.push("-wal");
            PathBuf::from(name)
        });
        let store = Store {
            conn,
            wal,
            fsyncs: Arc::new(AtomicU64::new(0)),
        };
        Ok((store, Loaded { epoch, events }))
    }

    /// Make the last commit durable: fsync the write-ahead log (what SQLite's
    /// `synchronous = FULL` does at each commit, done here so that it is counted).
    fn sync(&self) -> Result<(), StreamError> {
        let Some(wal) = &self.wal else {
            return Ok(());
        };
        let file = std::fs::File::open(wal)
            .map_err(|e| StreamError::State(format!("{}: {e}", wal.display())))?;
        file.sync_data()
            .map_err(|e| StreamError::State(format!("fsync {}: {e}", wal.display())))?;
        self.fsyncs.fetch_add(1, Ordering::Release);
        Ok(())
    }

    /// Write one event and its derived rows atomically.
    pub fn append(&mut self, event: &Event, json: &str) -> Result<(), StreamError> {
        let tx = self.conn.transaction().map_err(db)?;
        let kind = match event {
            Event::Progress {
                seq,
                unit,
                by,
                op_id,
                ..
            } => {
                tx.execute(
                    "INSERT INTO completed (unit, op_id, client_id, seq) VALUES (?1, ?2, ?3, ?4)",
                    params![unit, op_id, by, *seq as i64],
                )
                .map_err(db)?;
                tx.execute("DELETE FROM claims WHERE unit = ?1", [unit])
                    .map_err(db)?;
                "progress"
            }
            Event::Claimed { seq, unit, by } => {
                tx.execute(
                    "INSERT OR REPLACE INTO claims (unit, client_id, seq) VALUES (?1, ?2, ?3)",
                    params![unit, by, *seq as i64],
                )
                .map_err(db)?;
                "claimed"
            }
            Event::Released { unit, .. } => {
                tx.execute("DELETE FROM claims WHERE unit = ?1", [unit])
                    .map_err(db)?;
                "released"
            }
            Event::Reopened { unit, .. } => {
                tx.execute("DELETE FROM completed WHERE unit = ?1", [unit])
                    .map_err(db)?;
                "reopened"
            }
            Event::Registration { seq, transform, .. } => {
                let t = serde_json::to_string(transform).unwrap_or_default();
                tx.execute(
                    "INSERT OR REPLACE INTO registration (id, json, seq) VALUES (1, ?1, ?2)",
                    params![t, *seq as i64],
                )
                .map_err(db)?;
                "registration"
            }
        };
        tx.execute(
            "INSERT INTO events (seq, kind, json) VALUES (?1, ?2, ?3)",
            params![event.seq() as i64, kind, json],
        )
        .map_err(db)?;
        tx.commit().map_err(db)?;
        self.sync()
    }
}

/// One measurement row.
pub(crate) struct Measurement {
    pub t_ms: u64,
    pub client_id: String,
    pub kind: &'static str,
    pub unit: String,
    pub json: String,
}

/// Batches measurements into the state file on its own thread.
pub(crate) struct MeasurementWriter {
    tx: Option<mpsc::SyncSender<Measurement>>,
    thread: Option<JoinHandle<()>>,
}

/// Told about measurements that could not be written: (client id, how many, why).
pub(crate) type OnWriteFailure = Box<dyn Fn(&str, u64, &str) + Send>;

/// Queue length of the measurement writer; beyond it measurements are dropped (and counted).
pub(crate) const MEASUREMENT_QUEUE: usize = 65_536;

impl MeasurementWriter {
    /// Start the writer on `path` (nothing is written when `None`). Rows that fail are
    /// counted in `failed` and reported through `on_failure`, per client.
    pub fn start(
        path: Option<&Path>,
        max_pages: Option<u64>,
        failed: Arc<AtomicU64>,
        on_failure: OnWriteFailure,
    ) -> Result<Self, StreamError> {
        let Some(path) = path else {
            return Ok(Self {
                tx: None,
                thread: None,
            });
        };
        let mut conn = Connection::open(path).map_err(db)?;
        conn.busy_timeout(std::time::Duration::from_secs(5))
            .map_err(db)?;
        if let Some(pages) = max_pages {
            conn.pragma_update(None, "max_page_count", pages as i64)
                .map_err(db)?;
        }
        let (tx, rx) = mpsc::sync_channel::<Measurement>(MEASUREMENT_QUEUE);
        let thread = std::thread::spawn(move || {
            while let Ok(first) = rx.recv() {
                let mut batch = vec![first];
                while let Ok(m) = rx.try_recv() {
                    batch.push(m);
                    if batch.len() >= 4096 {
                        break;
                    }
                }
                if let Err(e) = write_batch(&mut conn, &batch) {
                    failed.fetch_add(batch.len() as u64, Ordering::Relaxed);
                    let mut per_client: Vec<(&str, u64)> = Vec::new();
                    for m in &batch {
                        match per_client.iter_mut().find(|(c, _)| *c == m.client_id) {
                            Some(entry) => entry.1 += 1,
                            None => per_client.push((&m.client_id, 1)),
                        }
                    }
                    let why = e.to_string();
                    for (client, n) in per_client {
                        on_failure(client, n, &why);
                    }
                }
            }
        });
        Ok(Self {
            tx: Some(tx),
            thread: Some(thread),
        })
    }

    /// Queue a measurement; false when the queue is full or there is no file.
    pub fn push(&self, m: Measurement) -> bool {
        self.tx.as_ref().is_some_and(|tx| tx.try_send(m).is_ok())
    }

    /// Flush and stop.
    pub fn stop(&mut self) {
        self.tx = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for MeasurementWriter {
    fn drop(&mut self) {
        self.stop();
    }
}

/// Write a batch in one transaction (all or nothing).
fn write_batch(conn: &mut Connection, batch: &[Measurement]) -> rusqlite::Result<()> {
    let txn = conn.transaction()?;
    for m in batch {
        txn.execute(
            "INSERT INTO measurements (t_ms, client_id, kind, unit, json) \
             VALUES (?1, ?2, ?3, ?4, ?5)",
            params![m.t_ms as i64, m.client_id, m.kind, m.unit, m.json],
        )?;
    }
    txn.commit()
}

/// A fresh epoch: 16 hex digits from the clock, the process id and a counter.
pub(crate) fn new_epoch() -> String {
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos())
        .unwrap_or(0);
    let mut h = Fnv::default();
    h.write(&nanos.to_le_bytes());
    h.write(&std::process::id().to_le_bytes());
    h.write(&COUNTER.fetch_add(1, Ordering::Relaxed).to_le_bytes());
    format!("{:016x}", h.0)
}

/// FNV-1a 64, stable across Rust versions (frame hashes in state files).
pub(crate) struct Fnv(pub u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    /// Mix bytes in.
    pub fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.0 ^= u64::from(*b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
}
