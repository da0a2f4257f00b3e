//! [`SimWorld`]: the rapier2d world of a scenario — walls, obstacles and the robot's body.
//!
//! One struct owns every rapier set and steps them with fixed [`IntegrationParameters`], `()` for
//! hooks and events. Bevy is not needed to use it. The world is top-down: no gravity; the floor's
//! grip is modelled per wheel by [`crate::drive`], which pushes on the body each step.
//!
//! The sonar's rays are cast against a [`Compound`] of the room's walls and obstacles, built once:
//! they never move and the robot is transparent to its own sonar, so no per-leaf filter is
//! needed. A 5-ray measurement costs ~0.9 µs this way against ~1.1 µs through the broad phase's
//! tree (`explobot bench`, furnished room); the hits are the same (the scenario snapshots did not
//! change).
//!
//! Collisions are counted as *contact starts*: each time the robot begins touching a wall or an
//! obstacle it was not touching in the previous step, the count goes up by one. Each fixed shape
//! carries what it is to the sonar ([`Touched`]), so a report can say what the robot touched.
//!
//! The speed guard: after every step the world checks that the body moves no faster than its
//! wheels can drive it ([`SimWorld::unphysical`]).

use std::collections::BTreeSet;

use rapier2d::parry::shape::{CompositeShapeRef, Compound};
use rapier2d::prelude::*;
use robot_model::kinematics::MecanumKinematics;
use robot_model::pose::Pose2;
use robot_model::profile::RobotProfile;

use crate::grid::room_edges;
use crate::scenario::Scenario;

mod touched;

use touched::segment_off_grid;
pub use touched::{LEG_MAX_M, Touched, WALL_MAX_THICKNESS_M, WALL_MIN_LENGTH_M};

/// Separation below which the robot starts touching something, metres. Rapier reports contact
/// pairs from 2 cm apart (its prediction distance) and its manifold distances date from before
/// the solver moved the bodies, so touching is decided from the true shape distance.
pub(crate) const TOUCH: f32 = 0.001;
/// Separation above which a touch has ended (hysteresis: sliding along a wall with the gap
/// hovering around [`TOUCH`] is one collision, not many).
const RELEASE: f32 = 0.005;
/// How far apart two shapes may be for the query that finds where a new contact is, metres
/// (a push can come from a millimetre or two away).
const TOUCH_QUERY_M: f32 = 0.01;

/// A ray that hit something.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayHit {
    /// Distance from the ray's origin, metres.
    pub distance: f32,
    /// Angle between the ray and the surface normal, radians (0 = head-on).
    pub incidence: f32,
    /// Which fixed shape it hit: the room's edges first, then the obstacles in the scenario's
    /// order (the index of [`ContactStart::part`]).
    pub part: usize,
}

/// A contact that started: what the robot touched, and where.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactStart {
    /// What it is.
    pub touched: Touched,
    /// Which fixed shape ([`RayHit::part`]).
    pub part: usize,
    /// Where the shapes meet (the deepest point when they overlap), world metres.
    pub at: (f32, f32),
    /// How fast the robot's surface closed on the shape when the contact began, m/s: the
    /// velocity of the robot's touching point before the step, along the contact normal
    /// (0 when it was moving away or the query failed).
    pub approach_m_s: f32,
    /// Which pair this is ([`SimWorld::contacts_ended`] names it again when it ends).
    pub key: ContactKey,
}

/// One robot–shape contact, from its start to its end (the shape's collider handle).
pub type ContactKey = (u32, u32);

/// The physics world of one scenario.
pub struct SimWorld {
    bodies: RigidBodySet,
    colliders: ColliderSet,
    islands: IslandManager,
    broad_phase: BroadPhaseBvh,
    narrow_phase: NarrowPhase,
    impulse_joints: ImpulseJointSet,
    multibody_joints: MultibodyJointSet,
    soft_bodies: SoftBodySet,
    ccd: CCDSolver,
    pipeline: PhysicsPipeline,
    params: IntegrationParameters,
    /// Walls and obstacles for the sonar's rays (`None` only for a room without any shape).
    fixed_scene: Option<Compound>,
    robot: RigidBodyHandle,
    robot_collider: ColliderHandle,
    half_length: f32,
    bumper_half_width: f32,
    touching: BTreeSet<(u32, u32)>,
    /// What each fixed shape is, by its collider's `user_data`.
    shape_kinds: Vec<Touched>,
    /// The contacts that started in the last step.
    started: Vec<ContactStart>,
    /// The contacts that ended in the last step.
    ended: Vec<ContactKey>,
    /// The robot's linear (m/s) and angular (rad/s) velocity and centre before the last step.
    before_step: ((f32, f32), f32, (f32, f32)),
    collisions: u32,
    front_contact: bool,
    speed_limit: SpeedLimit,
    unphysical: Unphysical,
    steps: u64,
}

/// The fastest the robot can move on its own wheels, with a margin: nothing else in the room
/// moves and contacts do not bounce (restitution 0), so a body going faster was thrown by a fault
/// of the simulation, not by anything physical.
#[derive(Debug, Clone, Copy)]
struct SpeedLimit {
    /// m/s.
    linear: f32,
    /// rad/s.
    angular: f32,
}

impl SpeedLimit {
    /// A quarter above the fastest body speed and turn rate that any mix of full-speed wheels
    /// gives through the profile's kinematics (strafing beats driving forward when the rollers
    /// sit below 45°): about 1.5 m/s and 8.1 rad/s for the default robot. Driving into a box's
    /// corner 10 cm off the centre line at top speed turns it at 5.6 rad/s (`tests/physics.rs`).
    fn of(profile: &RobotProfile) -> SpeedLimit {
        let kinematics = MecanumKinematics::from_profile(profile);
        let full = profile.motor.max_wheel_rpm;
        let (mut linear, mut angular) = (0.0f32, 0.0f32);
        for signs in 0..16u32 {
            let rpm = std::array::from_fn(|i| if signs >> i & 1 == 1 { full } else { -full });
            let twist = kinematics.forward_rpm(rpm);
            linear = linear.max(twist.vx.hypot(twist.vy));
            angular = angular.max(twist.omega.abs());
        }
        SpeedLimit { linear: 1.25 * linear, angular: 1.25 * angular }
    }
}

/// Steps after which the body moved faster than its wheels can drive it (see
/// [`SimWorld::unphysical`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Unphysical {
    /// How many steps.
    pub steps: u32,
    /// Simulated time after the first such step, seconds (`None` when there was none).
    pub first_at_s: Option<f64>,
    /// The fastest body speed after any step, m/s.
    pub fastest_m_s: f32,
    /// The fastest body turn rate after any step, rad/s.
    pub fastest_rad_s: f32,
}

impl Unphysical {
    /// One line for a report: "sound" with the fastest speeds, or when and how often the body
    /// went faster than its wheels can drive it.
    pub fn describe(&self) -> String {
        let fastest = format!("fastest {:.2} m/s, {:.1} rad/s", self.fastest_m_s, self.fastest_rad_s);
        match self.first_at_s {
            None => format!("sound ({fastest})"),
            Some(t) => format!(
                "NOT PHYSICAL from {t:.3} s: the body moved faster than its wheels can drive it \
                 ({} steps, {fastest})",
                self.steps
            ),
        }
    }
}

impl SimWorld {
    /// Builds the room, its obstacles and the robot at `start` (world pose).
    pub fn new(scenario: &Scenario, profile: &RobotProfile, start: Pose2, dt: f32) -> SimWorld {
        let mut bodies = RigidBodySet::new();
        let mut colliders = ColliderSet::new();
        let ground = bodies.insert(RigidBodyBuilder::fixed());
        let walls = room_edges(&scenario.room).map(|wall| {
            let (a, b) = (wall.a, wall.b);
            let kind = Touched::RoomWall { off_grid_deg: segment_off_grid((a.x, a.y), (b.x, b.y)) };
            ((Pose::IDENTITY, SharedShape::new(wall)), kind)
        });
        let obstacles = scenario.obstacles.iter().filter_map(|o| {
            let (pose, shape) = o.shape()?;
            Some(((pose, SharedShape(std::sync::Arc::from(shape))), Touched::of(o)))
        });
        let (fixed_shapes, shape_kinds): (Vec<(Pose, SharedShape)>, Vec<Touched>) =
            walls.chain(obstacles).unzip();
        for (i, (pose, shape)) in fixed_shapes.iter().enumerate() {
            let collider =
                ColliderBuilder::new(shape.clone()).position(*pose).friction(0.3).user_data(i as u128);
            colliders.insert_with_parent(collider, ground, &mut bodies);
        }
        // Every shape here is a simple one (segment, cuboid, ball, convex polygon), which is all
        // `Compound::new` asks for besides a non-empty list.
        let fixed_scene = (!fixed_shapes.is_empty()).then(|| Compound::new(fixed_shapes));
        let half_length = profile.geometry.body_length_m * 0.5;
        // No CCD: at its top speed (1.2 m/s) the robot moves 6 mm per 5 ms step, far less than
        // its 24 cm width, so it cannot tunnel through a wall (the physics tests check it);
        // CCD cost ~10 % of the step time.
        let robot = bodies.insert(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(start.x, start.y))
                .rotation(start.theta)
                .can_sleep(false),
        );
        let robot_collider = colliders.insert_with_parent(
            ColliderBuilder::cuboid(half_length, profile.geometry.body_width_m * 0.5)
                .mass(profile.geometry.mass_kg)
                .friction(0.3)
                .restitution(0.0),
            robot,
            &mut bodies,
        );
        // No contact recycling: a contact point kept from an earlier step let a table leg 1 cm
        // beside the body push the robot 7 mm off its track, as if the robot were a centimetre
        // wider than it is (issue 10, measured-default; `sim/twin/tests/physics.rs`). Costs nothing
        // measurable (`explobot bench`).
        let params =
            IntegrationParameters { dt, contact_recycling: false, ..IntegrationParameters::default() };
        let mut world = SimWorld {
            bodies,
            colliders,
            islands: IslandManager::new(),
            broad_phase: BroadPhaseBvh::new(),
            narrow_phase: NarrowPhase::new(),
            impulse_joints: ImpulseJointSet::new(),
            multibody_joints: MultibodyJointSet::new(),
            soft_bodies: SoftBodySet::new(),
            ccd: CCDSolver::new(),
            pipeline: PhysicsPipeline::new(),
            params,
            fixed_scene,
            robot,
            robot_collider,
            half_length,
            bumper_half_width: profile.bumper.face_width_m * 0.5,
            touching: BTreeSet::new(),
            shape_kinds,
            started: Vec::new(),
            ended: Vec::new(),
            before_step: ((0.0, 0.0), 0.0, (0.0, 0.0)),
            collisions: 0,
            front_contact: false,
            speed_limit: SpeedLimit::of(profile),
            unphysical: Unphysical::default(),
            steps: 0,
        };
        // A zero-length step builds the broad phase and the contact graph before the first real
        // step (kept because the recorded runs and snapshots start from that state).
        world.params.dt = 0.0;
        world.step();
        world.params.dt = dt;
        world
    }

    /// Advances the world by one fixed step (the `dt` given to [`SimWorld::new`]).
    pub fn step(&mut self) {
        if let Some(b) = self.bodies.get(self.robot) {
            let (v, c) = (b.linvel(), b.translation());
            self.before_step = ((v.x, v.y), b.angvel(), (c.x, c.y));
        }
        self.pipeline.step(
            Vector::ZERO,
            &self.params,
            &mut self.islands,
            &mut self.broad_phase,
            &mut self.narrow_phase,
            &mut self.bodies,
            &mut self.colliders,
            &mut self.impulse_joints,
            &mut self.multibody_joints,
            &mut self.soft_bodies,
            &mut self.ccd,
            &(),
            &(),
        );
        self.update_contacts();
        if self.params.dt > 0.0 {
            self.steps += 1;
            self.check_speed();
        }
    }

    fn check_speed(&mut self) {
        let Some(body) = self.bodies.get(self.robot) else {
            return;
        };
        let (speed, turn) = (body.linvel().length(), body.angvel().abs());
        let u = &mut self.unphysical;
        u.fastest_m_s = u.fastest_m_s.max(speed);
        u.fastest_rad_s = u.fastest_rad_s.max(turn);
        if speed > self.speed_limit.linear || turn > self.speed_limit.angular {
            u.steps += 1;
            if u.first_at_s.is_none() {
                // Whole microseconds: the f32 step would give 0.0249999994 s for 0.025 s.
                let at_s = self.steps as f64 * f64::from(self.params.dt);
                u.first_at_s = Some((at_s * 1e6).round() / 1e6);
                let at = body.translation();
                tracing::warn!(speed, turn, ?at, "the body moved faster than its wheels can drive it");
            }
        }
    }

    fn update_contacts(&mut self) {
        let mut now_touching = BTreeSet::new();
        let mut front = false;
        let Some(robot) = self.colliders.get(self.robot_collider) else {
            return;
        };
        for pair in self.narrow_phase.contact_pairs_with(self.robot_collider) {
            if !pair.has_any_active_contact() {
                continue;
            }
            let other = if pair.collider1 == self.robot_collider { pair.collider2 } else { pair.collider1 };
            let Some(obstacle) = self.colliders.get(other) else {
                continue;
            };
            let gap = rapier2d::parry::query::distance(
                robot.position(),
                robot.shape(),
                obstacle.position(),
                obstacle.shape(),
            )
            .map_or(0.0, |d| d.distance);
            // A speculative contact can stop the robot a millimetre or two short of an obstacle
            // (measured-clutter seed 17: a leg pushed back with 0.4–1.0 N·s at gaps of 1.2–2.2 mm
            // while the robot spun after a crash), so the gap never closes to TOUCH. A push is a
            // touch.
            let pushed = pair.total_impulse_magnitude() > 0.0;
            let key = other.into_raw_parts();
            let limit = if self.touching.contains(&key) { RELEASE } else { TOUCH };
            if gap > limit && !pushed {
                continue;
            }
            now_touching.insert(key);
            let robot_is_first = pair.collider1 == self.robot_collider;
            front |= (gap <= TOUCH || pushed)
                && front_face_touched(
                    pair.manifolds(),
                    robot_is_first,
                    self.half_length,
                    self.bumper_half_width,
                );
        }
        let new_keys: Vec<(u32, u32)> = now_touching.difference(&self.touching).copied().collect();
        self.ended = self.touching.difference(&now_touching).copied().collect();
        let ((vx, vy), omega, (cx, cy)) = self.before_step;
        self.started = new_keys
            .iter()
            .filter_map(|&(index, generation)| {
                let collider = self.colliders.get(ColliderHandle::from_raw_parts(index, generation))?;
                let part = collider.user_data as usize;
                // where the shapes meet (the deepest point when they overlap); the robot's centre
                // if the query fails
                let contact = rapier2d::parry::query::contact(
                    robot.position(),
                    robot.shape(),
                    collider.position(),
                    collider.shape(),
                    TOUCH_QUERY_M,
                )
                .ok()
                .flatten();
                let at = contact.map_or(robot.translation(), |c| c.point2);
                // The touching point's velocity before the step (v + ω × r), along the robot's
                // outward normal.
                let approach_m_s = contact.map_or(0.0, |c| {
                    let (rx, ry) = (c.point1.x - cx, c.point1.y - cy);
                    let (px, py) = (vx - omega * ry, vy + omega * rx);
                    (px * c.normal1.x + py * c.normal1.y).max(0.0)
                });
                Some(ContactStart {
                    touched: *self.shape_kinds.get(part)?,
                    part,
                    at: (at.x, at.y),
                    approach_m_s,
                    key: (index, generation),
                })
            })
            .collect();
        let started = new_keys.len() as u32;
        if started > 0 {
            let at = self.robot_body().map(|b| b.translation());
            tracing::debug!(?at, front, "collision: contact started");
        }
        self.collisions += started;
        self.touching = now_touching;
        self.front_contact = front;
    }

    fn robot_body(&self) -> Option<&RigidBody> {
        self.bodies.get(self.robot)
    }

    /// The robot's pose in the world.
    pub fn robot_pose(&self) -> Pose2 {
        match self.robot_body() {
            Some(b) => {
                let t = b.translation();
                Pose2 { x: t.x, y: t.y, theta: b.rotation().angle() }
            }
            None => Pose2::default(),
        }
    }

    /// Velocity (world frame) of the robot's material point at body-frame offset (bx, by).
    pub fn robot_point_velocity(&self, bx: f32, by: f32) -> (f32, f32) {
        match self.robot_body() {
            Some(b) => {
                let p = b.position().transform_point(Vector::new(bx, by));
                let v = b.velocity_at_point(p);
                (v.x, v.y)
            }
            None => (0.0, 0.0),
        }
    }

    /// Clears the forces and torques of the previous step. Rapier keeps both until they are
    /// reset, and a force off the centre of mass adds a torque: when only the forces were cleared
    /// the wheels' torques summed over the whole run, and a robot jammed while turning was thrown
    /// across the room at 20 m/s after a few seconds (40 of 200 generated rooms).
    pub fn reset_robot_forces(&mut self) {
        if let Some(b) = self.bodies.get_mut(self.robot) {
            b.reset_forces(true);
            b.reset_torques(true);
        }
    }

    /// Pushes on the robot with a world-frame force (N) at body-frame offset (bx, by).
    pub fn add_robot_force(&mut self, bx: f32, by: f32, fx: f32, fy: f32) {
        if let Some(b) = self.bodies.get_mut(self.robot) {
            let p = b.position().transform_point(Vector::new(bx, by));
            b.add_force_at_point(Vector::new(fx, fy), p, true);
        }
    }

    /// Casts a ray from world point `origin` along unit `dir` against the walls and obstacles
    /// (the robot itself is transparent). A miss within `max` metres is `None`.
    pub fn cast_range(&self, origin: (f32, f32), dir: (f32, f32), max: f32) -> Option<RayHit> {
        let ray = Ray::new(Vector::new(origin.0, origin.1), Vector::new(dir.0, dir.1));
        let (part, hit) =
            CompositeShapeRef(self.fixed_scene.as_ref()?).cast_local_ray_and_get_normal(&ray, max, true)?;
        // Angle between the reversed ray and the surface normal.
        let cos = -(dir.0 * hit.normal.x + dir.1 * hit.normal.y);
        Some(RayHit {
            distance: hit.time_of_impact,
            incidence: cos.abs().clamp(0.0, 1.0).acos(),
            part: part as usize,
        })
    }

    /// The steps after which the robot moved faster than its wheels can drive it. None should
    /// ever happen; a run with one did something unphysical from then on, and its report says so
    /// (`docs/explanation/physical-model.md`, "Contacts").
    pub fn unphysical(&self) -> Unphysical {
        self.unphysical
    }

    /// How many times the robot has started touching something.
    pub fn collisions(&self) -> u32 {
        self.collisions
    }

    /// The contacts that ended in the last step (each named as it started, [`ContactStart::key`]).
    pub fn contacts_ended(&self) -> &[ContactKey] {
        &self.ended
    }

    /// The robot's velocity now: linear (world, m/s) and angular (rad/s, counter-clockwise).
    pub fn robot_velocity(&self) -> ((f32, f32), f32) {
        self.robot_body().map_or(((0.0, 0.0), 0.0), |b| ((b.linvel().x, b.linvel().y), b.angvel()))
    }

    /// The contacts that started in the last step (empty when none did).
    pub fn contacts_started(&self) -> &[ContactStart] {
        &self.started
    }

    /// Whether anything touches the robot's front face now (the bumper).
    pub fn front_contact(&self) -> bool {
        self.front_contact
    }

    /// The fixed step, seconds.
    pub fn dt(&self) -> f32 {
        self.params.dt
    }
}

/// Whether something touching the robot (the caller checked) presses on its bumper: a contact
/// point on the front face within the bumper's width (corners included when the bumper spans the
/// face), whose normal, leaving the robot, points within 45° of straight ahead. A wall grazing
/// the robot's side while it turns does not press the bumper.
fn front_face_touched(
    manifolds: &[ContactManifold],
    robot_is_first: bool,
    half_length: f32,
    bumper_half_width: f32,
) -> bool {
    manifolds.iter().any(|m| {
        let normal = if robot_is_first { m.local_n1 } else { m.local_n2 };
        normal.x > std::f32::consts::FRAC_1_SQRT_2
            && m.points.iter().any(|p| {
                let local = if robot_is_first { p.local_p1 } else { p.local_p2 };
                local.x > half_length - 0.01 && local.y.abs() <= bumper_half_width + 1e-3
            })
    })
}
