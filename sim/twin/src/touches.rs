//! Every touch of a run, with how hard it was and whether Carto noticed it.
//!
//! A *touch* is one contact between the robot and a wall or an obstacle, from when it starts to
//! when it ends ([`crate::world`]: within 1 mm, or pushing); a run's `collisions` counts them.
//! For each the tracker records:
//! - **approach speed**: how fast the robot's touching point closed on the shape, along the
//!   contact normal, in the step the contact began (m/s);
//! - **push**: the largest distance, over the contact, between where the body is and where its
//!   wheels drove it since the contact began — the body's displacement less the displacement its
//!   four wheel speeds give through the mecanum kinematics. A body held by a wall while its wheels
//!   drive on, or shoved sideways by a leg, moves away from what its encoders tell Carto; this is
//!   what leaves a robot lost;
//! - **noticed**: what in Carto saw it — its bumper, its push watch, or its stall watch, by the
//!   first of Carto's counters that rose between the contact's start and [`NOTICE_WINDOW_S`]
//!   after its end — or `unseen`;
//! - what Carto was doing when it began.
//!
//! A **hard collision** is a touch that began at [`HARD_APPROACH_M_S`] or more, or pushed the
//! body [`HARD_PUSH_M`] or more. Touches are what a bump-based robot lives with; a hard collision
//! is what must never happen.
//!
//! ```
//! use twin::touches::{Noticed, Touch};
//! let graze = Touch { t_s: 3.0, touched: None, approach_m_s: 0.02, push_m: 0.004,
//!     noticed: Noticed::Unseen, carto_activity: "turning".into(), duration_s: 0.4 };
//! assert!(!graze.is_hard());
//! let crash = Touch { approach_m_s: 0.36, ..graze.clone() };
//! assert!(crash.is_hard());
//! ```

use robot_model::kinematics::MecanumKinematics;
use serde::{Deserialize, Serialize};

use crate::world::{ContactKey, ContactStart, Touched};

/// A touch that began this fast or faster is a hard collision, m/s.
pub const HARD_APPROACH_M_S: f64 = 0.10;
/// A touch that pushed the body this far from where its wheels drove it is a hard collision,
/// metres.
pub const HARD_PUSH_M: f64 = 0.02;
/// How long after a touch ends a rise of Carto's counters still counts as noticing it, seconds
/// (its stall watch needs a few encoder samples).
pub const NOTICE_WINDOW_S: f64 = 1.0;

/// What in Carto noticed a touch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Noticed {
    /// The front bumper.
    Bumper,
    /// The push watch (the IMU saw the body turned under its wheels).
    Push,
    /// The stall watch (wheels turning, the range not closing).
    Stall,
    /// Nothing in Carto.
    Unseen,
}

/// One touch (see the module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Touch {
    /// When it began, sim seconds.
    pub t_s: f64,
    /// What was touched.
    pub touched: Option<Touched>,
    /// Approach speed, m/s.
    pub approach_m_s: f64,
    /// Push, metres.
    pub push_m: f64,
    /// What noticed it.
    pub noticed: Noticed,
    /// What Carto's pilot was doing when it began, in words.
    pub carto_activity: String,
    /// How long the contact lasted, seconds.
    pub duration_s: f64,
}

impl Touch {
    /// Whether it is a hard collision.
    pub fn is_hard(&self) -> bool {
        self.approach_m_s >= HARD_APPROACH_M_S || self.push_m >= HARD_PUSH_M
    }
}

/// The touches of a run, as the report gives them.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TouchReport {
    /// Touches (the run's `collisions`).
    pub count: u32,
    /// Hard collisions among them.
    pub hard: u32,
    /// Touches nothing in Carto noticed.
    pub unseen: u32,
    /// Touches per 100 moves Cute sent (the count itself when no move was sent).
    pub per_100_moves: f64,
    /// The fastest approach of any touch, m/s.
    pub fastest_approach_m_s: f64,
    /// The largest push of any touch, metres.
    pub largest_push_m: f64,
    /// Every touch, in order (left out of a sweep's `results.jsonl` lines).
    #[serde(default)]
    pub list: Vec<Touch>,
}

/// Carto's counters that tell a touch was noticed: bumper presses, push stops, stall stops.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct NoticeCounters {
    /// Bumper presses.
    pub bumps: u64,
    /// FORWARDs stopped as pushed.
    pub pushes: u64,
    /// FORWARDs stopped as stalled.
    pub stalls: u64,
}

/// What the body and its wheels did in one step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepMotion {
    /// The body's velocity, world frame, m/s.
    pub body_velocity: (f32, f32),
    /// Its heading, radians counter-clockwise from +x.
    pub heading: f32,
    /// The four wheel speeds, rpm (FL, FR, RL, RR).
    pub wheel_rpm: [f32; 4],
}

#[derive(Debug, Clone)]
struct Open {
    key: ContactKey,
    touch: Touch,
    displaced: (f64, f64),
    counters: NoticeCounters,
    ended_at_s: Option<f64>,
}

/// Follows the touches of a run step by step.
#[derive(Debug, Clone)]
pub struct TouchTracker {
    kinematics: MecanumKinematics,
    open: Vec<Open>,
    done: Vec<Touch>,
}

impl TouchTracker {
    /// A tracker for a robot with these wheel kinematics.
    pub fn new(kinematics: MecanumKinematics) -> TouchTracker {
        TouchTracker { kinematics, open: Vec::new(), done: Vec::new() }
    }

    /// One physics step of `dt_s` ending at `t_s`: the contacts that `started` and `ended` in it,
    /// the `motion` over it, Carto's `counters` now and what it is doing (`activity`, asked only
    /// when a contact starts).
    pub fn step(
        &mut self,
        t_s: f64,
        dt_s: f64,
        (started, ended): (&[ContactStart], &[ContactKey]),
        motion: StepMotion,
        counters: NoticeCounters,
        activity: impl Fn() -> String,
    ) {
        let twist = self.kinematics.forward_rpm(motion.wheel_rpm);
        let (sin, cos) = motion.heading.sin_cos();
        let wheels = (twist.vx * cos - twist.vy * sin, twist.vx * sin + twist.vy * cos);
        let slip =
            (f64::from(motion.body_velocity.0 - wheels.0), f64::from(motion.body_velocity.1 - wheels.1));
        for o in self.open.iter_mut().filter(|o| o.ended_at_s.is_none()) {
            o.displaced.0 += slip.0 * dt_s;
            o.displaced.1 += slip.1 * dt_s;
            o.touch.push_m = o.touch.push_m.max(o.displaced.0.hypot(o.displaced.1));
            if ended.contains(&o.key) {
                o.ended_at_s = Some(t_s);
                o.touch.duration_s = t_s - o.touch.t_s;
            }
        }
        for c in started {
            self.open.push(Open {
                key: c.key,
                touch: Touch {
                    t_s,
                    touched: Some(c.touched),
                    approach_m_s: f64::from(c.approach_m_s),
                    push_m: 0.0,
                    noticed: Noticed::Unseen,
                    carto_activity: activity(),
                    duration_s: 0.0,
                },
                displaced: (0.0, 0.0),
                counters,
                ended_at_s: None,
            });
        }
        for o in &mut self.open {
            if o.touch.noticed == Noticed::Unseen {
                o.touch.noticed = noticed(o.counters, counters);
            }
        }
        let (closed, open): (Vec<Open>, Vec<Open>) = std::mem::take(&mut self.open)
            .into_iter()
            .partition(|o| o.ended_at_s.is_some_and(|end| t_s - end >= NOTICE_WINDOW_S));
        self.open = open;
        self.done.extend(closed.into_iter().map(|o| o.touch));
    }

    /// The report of every touch so far (those still open as they stand), over `moves` moves.
    pub fn report(&self, moves: u64, t_s: f64) -> TouchReport {
        let mut list = self.done.clone();
        list.extend(self.open.iter().map(|o| {
            let mut t = o.touch.clone();
            if o.ended_at_s.is_none() {
                t.duration_s = t_s - t.t_s;
            }
            t
        }));
        list.sort_by(|a, b| a.t_s.total_cmp(&b.t_s));
        let count = list.len() as u32;
        TouchReport {
            count,
            hard: list.iter().filter(|t| t.is_hard()).count() as u32,
            unseen: list.iter().filter(|t| t.noticed == Noticed::Unseen).count() as u32,
            per_100_moves: if moves == 0 {
                f64::from(count)
            } else {
                100.0 * f64::from(count) / moves as f64
            },
            fastest_approach_m_s: list.iter().map(|t| t.approach_m_s).fold(0.0, f64::max),
            largest_push_m: list.iter().map(|t| t.push_m).fold(0.0, f64::max),
            list,
        }
    }
}

/// What noticed a touch, from Carto's counters when it began and now.
fn noticed(then: NoticeCounters, now: NoticeCounters) -> Noticed {
    if now.bumps > then.bumps {
        Noticed::Bumper
    } else if now.pushes > then.pushes {
        Noticed::Push
    } else if now.stalls > then.stalls {
        Noticed::Stall
    } else {
        Noticed::Unseen
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use robot_model::profile::RobotProfile;

    fn start(key: ContactKey, approach: f32) -> ContactStart {
        ContactStart {
            touched: Touched::Leg { width_m: 0.04 },
            part: 4,
            at: (0.0, 0.0),
            approach_m_s: approach,
            key,
        }
    }

    fn still() -> StepMotion {
        StepMotion { body_velocity: (0.0, 0.0), heading: 0.0, wheel_rpm: [0.0; 4] }
    }

    #[test]
    fn a_body_held_while_its_wheels_drive_on_is_pushed_by_what_they_drove() {
        let k = MecanumKinematics::from_profile(&RobotProfile::default());
        let mut t = TouchTracker::new(k);
        let none = NoticeCounters::default();
        t.step(1.0, 0.005, (&[start((1, 0), 0.05)], &[]), still(), none, || "driving forward".into());
        // 0.2 s with the wheels at 60 rpm forward and the body held: 0.245 m/s × 0.2 s ≈ 4.9 cm.
        let held = StepMotion { wheel_rpm: [60.0; 4], ..still() };
        for i in 0..40 {
            t.step(1.0 + 0.005 * f64::from(i + 1), 0.005, (&[], &[]), held, none, String::new);
        }
        let r = t.report(10, 1.2);
        assert_eq!(r.count, 1);
        let touch = &r.list[0];
        let want = 60.0 / 60.0 * std::f64::consts::TAU * 0.039 * 0.2;
        assert!((touch.push_m - want).abs() < 1e-3, "{touch:?} want {want}");
        assert!(touch.is_hard() && r.hard == 1, "a 5 cm push is hard although it began at 5 cm/s");
        assert_eq!(touch.carto_activity, "driving forward");
        assert_eq!(r.per_100_moves, 10.0);
    }

    #[test]
    fn a_touch_is_noticed_by_the_first_counter_that_rises_until_a_second_after_it_ends() {
        let k = MecanumKinematics::from_profile(&RobotProfile::default());
        let mut t = TouchTracker::new(k);
        let none = NoticeCounters::default();
        t.step(1.0, 0.005, (&[start((1, 0), 0.2)], &[]), still(), none, String::new);
        t.step(1.5, 0.005, (&[start((2, 0), 0.0)], &[(1, 0)]), still(), none, String::new);
        t.step(2.0, 0.005, (&[], &[(2, 0)]), still(), none, String::new);
        // A stall stop 0.9 s after the first ended: both noticed. Nothing rises after.
        let stalled = NoticeCounters { stalls: 1, ..none };
        t.step(2.4, 0.005, (&[], &[]), still(), stalled, String::new);
        t.step(9.0, 0.005, (&[start((3, 0), 0.0)], &[]), still(), stalled, String::new);
        t.step(9.1, 0.005, (&[], &[(3, 0)]), still(), stalled, String::new);
        t.step(12.0, 0.005, (&[], &[]), still(), stalled, String::new);
        let r = t.report(3, 12.0);
        let noticed: Vec<Noticed> = r.list.iter().map(|t| t.noticed).collect();
        assert_eq!(noticed, [Noticed::Stall, Noticed::Stall, Noticed::Unseen]);
        assert_eq!((r.count, r.unseen, r.hard), (3, 1, 1), "{r:?}");
        assert!((r.list[0].duration_s - 0.5).abs() < 1e-9);
        assert_eq!(r.fastest_approach_m_s, 0.2f32 as f64);
    }
}
