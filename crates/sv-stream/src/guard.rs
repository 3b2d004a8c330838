//! Admission on a busy LAN: per-address limits on connections and on pending handshakes
//! (accepted but not yet past `hello`), and throttling of wrong tokens per address, so that
//! one device (or one attacker) cannot lock out another.
//!
//! [`Guard::admit`] is asked at accept; the [`Ticket`] it returns holds the address's slots
//! until the connection ends ([`Ticket::authenticated`] moves it from pending to open).
//! Wrong tokens draw from a per-address bucket ([`Guard::check_auth`], [`Guard::auth_failed`]).

use std::collections::HashMap;
use std::net::IpAddr;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Limits per source address.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AddressLimits {
    /// Most connections of one address (pending or authenticated).
    pub connections: usize,
    /// Most connections of one address that have not yet sent a good `hello` (TCP or TLS
    /// open, HTTP head being read, websocket waiting for `hello`).
    pub pending: usize,
    /// Wrong tokens one address may send in a burst ...
    pub auth_burst: f64,
    /// ... then this many per second.
    pub auth_per_second: f64,
}

impl Default for AddressLimits {
    fn default() -> Self {
        Self {
            connections: 64,
            pending: 16,
            auth_burst: 5.0,
            auth_per_second: 0.5,
        }
    }
}

#[derive(Debug)]
struct Address {
    open: usize,
    pending: usize,
    /// Wrong-token bucket and when it was last refilled.
    tokens: f64,
    refilled: Instant,
}

/// Why a connection was refused at accept.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refused {
    /// The address holds its limit of connections.
    Connections,
    /// The address holds its limit of pending handshakes.
    Pending,
}

/// Counters of what the guard refused (for [`crate::Stats`]).
#[derive(Debug, Default)]
pub struct GuardCounts {
    /// Connections refused at accept because their address was at a limit.
    pub refused: AtomicU64,
    /// `hello`s with a wrong token.
    pub auth_failures: AtomicU64,
    /// `hello`s refused unread because their address sent too many wrong tokens.
    pub auth_throttled: AtomicU64,
}

/// Per-address bookkeeping, shared by the accept loop and the connections.
#[derive(Debug)]
pub struct Guard {
    limits: AddressLimits,
    addresses: Mutex<HashMap<IpAddr, Address>>,
    /// What was refused.
    pub counts: GuardCounts,
}

/// One admitted connection's hold on its address's slots; released on drop.
#[derive(Debug)]
pub struct Ticket {
    guard: Arc<Guard>,
    ip: IpAddr,
    pending: bool,
}

impl Guard {
    /// A guard with these limits.
    pub fn new(limits: AddressLimits) -> Arc<Guard> {
        Arc::new(Guard {
            limits,
            addresses: Mutex::new(HashMap::new()),
            counts: GuardCounts::default(),
        })
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, HashMap<IpAddr, Address>> {
        self.addresses.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Admit a new connection from `ip`, as pending, unless its address is at a limit.
    pub fn admit(self: &Arc<Self>, ip: IpAddr, now: Instant) -> Result<Ticket, Refused> {
        let mut map = self.lock();
        let a = map.entry(ip).or_insert(Address {
            open: 0,
            pending: 0,
            tokens: self.limits.auth_burst,
            refilled: now,
        });
        let refused = if a.open >= self.limits.connections {
            Some(Refused::Connections)
        } else if a.pending >= self.limits.pending {
            Some(Refused::Pending)
        } else {
            None
        };
        if let Some(r) = refused {
            self.counts.refused.fetch_add(1, Ordering::Relaxed);
            return Err(r);
        }
        a.open += 1;
        a.pending += 1;
        Ok(Ticket {
            guard: self.clone(),
            ip,
            pending: true,
        })
    }

    fn refill(&self, a: &mut Address, now: Instant) {
        let dt = now.saturating_duration_since(a.refilled).as_secs_f64();
        a.tokens = (a.tokens + dt * self.limits.auth_per_second).min(self.limits.auth_burst);
        a.refilled = now;
    }

    /// `Ok` when `ip` may try a token now, else how long until it may.
    pub fn check_auth(&self, ip: IpAddr, now: Instant) -> Result<(), Duration> {
        let mut map = self.lock();
        let Some(a) = map.get_mut(&ip) else {
            return Ok(());
        };
        self.refill(a, now);
        if a.tokens >= 1.0 {
            Ok(())
        } else {
            self.counts.auth_throttled.fetch_add(1, Ordering::Relaxed);
            let wait = (1.0 - a.tokens) / self.limits.auth_per_second.max(1e-9);
            Err(Duration::from_secs_f64(wait.min(3600.0)))
        }
    }

    /// Count a wrong token from `ip`.
    pub fn auth_failed(&self, ip: IpAddr, now: Instant) {
        self.counts.auth_failures.fetch_add(1, Ordering::Relaxed);
        let mut map = self.lock();
        if let Some(a) = map.get_mut(&ip) {
            self.refill(a, now);
            a.tokens = (a.tokens - 1.0).max(0.0);
        }
    }

    /// Connections and pending handshakes `ip` holds now.
    pub fn held(&self, ip: IpAddr) -> (usize, usize) {
        self.lock().get(&ip).map_or((0, 0), |a| (a.open, a.pending))
    }
}

impl Ticket {
    /// The connection sent a good `hello`: it no longer counts as pending.
    pub fn authenticated(&mut self) {
        if self.pending {
            self.pending = false;
            if let Some(a) = self.guard.lock().get_mut(&self.ip) {
                a.pending = a.pending.saturating_sub(1);
            }
        }
    }

    /// The source address.
    pub fn ip(&self) -> IpAddr {
        self.ip
    }
}

impl Drop for Ticket {
    fn drop(&mut self) {
        let mut map = self.guard.lock();
        let remove = match map.get_mut(&self.ip) {
            Some(a) => {
                a.open = a.open.saturating_sub(1);
                if self.pending {
                    a.pending = a.pending.saturating_sub(1);
                }
                // forget an address with nothing open and nothing held against it
                a.open == 0 && a.tokens >= self.guard.limits.auth_burst
            }
            None => false,
        };
        if remove {
            map.remove(&self.ip);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ip(last: u8) -> IpAddr {
        IpAddr::from([127, 0, 0, last])
    }

    #[test]
    fn one_address_at_its_limit_does_not_block_another() {
        let g = Guard::new(AddressLimits {
            connections: 4,
            pending: 2,
            ..AddressLimits::default()
        });
        let now = Instant::now();
        let mut a: Vec<Ticket> = (0..2).map(|_| g.admit(ip(1), now).unwrap()).collect();
        assert_eq!(g.admit(ip(1), now).unwrap_err(), Refused::Pending);
        assert!(
            g.admit(ip(2), now).is_ok(),
            "another address is not affected"
        );
        // authenticated connections free their pending slot, up to the connection limit
        for t in &mut a {
            t.authenticated();
        }
        a.push(g.admit(ip(1), now).unwrap());
        a.push(g.admit(ip(1), now).unwrap());
        assert_eq!(g.held(ip(1)), (4, 2));
        assert_eq!(g.admit(ip(1), now).unwrap_err(), Refused::Connections);
        assert_eq!(g.counts.refused.load(Ordering::Relaxed), 2);
        a.clear();
        assert_eq!(g.held(ip(1)), (0, 0));
        assert!(g.admit(ip(1), now).is_ok());
    }

    #[test]
    fn wrong_tokens_are_throttled_per_address() {
        let g = Guard::new(AddressLimits {
            auth_burst: 3.0,
            auth_per_second: 0.5,
            ..AddressLimits::default()
        });
        let t0 = Instant::now();
        let _held = (g.admit(ip(1), t0).unwrap(), g.admit(ip(2), t0).unwrap());
        for _ in 0..3 {
            assert!(g.check_auth(ip(1), t0).is_ok());
            g.auth_failed(ip(1), t0);
        }
        let wait = g.check_auth(ip(1), t0).unwrap_err();
        assert!((wait.as_secs_f64() - 2.0).abs() < 1e-6, "{wait:?}");
        assert!(
            g.check_auth(ip(2), t0).is_ok(),
            "another address may still try"
        );
        // one more try after 2 s, not two
        let t1 = t0 + Duration::from_secs(2);
        assert!(g.check_auth(ip(1), t1).is_ok());
        g.auth_failed(ip(1), t1);
        assert!(g.check_auth(ip(1), t1).is_err());
        assert_eq!(g.counts.auth_failures.load(Ordering::Relaxed), 4);
    }
}
