//! One contact evaluated for a step: the kernels the force stage calls for
//! each particle-wall and particle-particle contact, and what one contact
//! hands to the books and the checks.
//!
//! A pair (Terzioglu's thesis eq. 3.1–3.8) or a wall contact (overlap eq.
//! 3.12, normal eq. 3.14) is turned into a [`ContactGeometry`] (R*, m*, δ, n
//! and the relative velocity of the contact points, whose lever arms are
//! eq. 3.27–3.28), evaluated by the contact law of [`crate::dem::contact`],
//! and given its torques (eq. 3.26) and, when it opens, the Hertz duration of
//! the collision (eq. 5.10) the checks hold against the time step; each
//! collision's steps are counted in its [`ContactState`] from the step it
//! begins to the step it ends, and handed to the books when it ends. The
//! kernels are instances for a law with or without damping (`D`) and friction
//! (`F`), always inlined into the loops of [`super::forces`] and
//! [`super::blocks`].
//!
//! A contact of a law whose multi-point contacts are shared
//! ([`MultiPoint::Shared`](crate::dem::contact::MultiPoint)) is given the
//! count `n` of sub-sphere contacts its body pair touches at this step
//! ([`super::shared_contacts`]) and carries `1/n` of one contact. When `n`
//! changes while it touches, the energy its normal spring stores changes
//! with the spring's stiffness at the same overlap: [`reshare`] books that
//! as stiffness work, as the tangential spring's is booked when k_t follows
//! the overlap.

use glam::DVec3;

use crate::dem::contact::{
    ContactGeometry, ContactLaw, ContactState, NormalDamping, Tangential, evaluate_contact_with,
};
use crate::dem::hertz_theory;
use crate::dem::material::{effective_mass_kg, effective_radius_m};
use crate::dem::walls::{WallShape, Walls};

/// The particle state contacts read, borrowed field by field from `$p` so
/// that its forces and torques stay free to write.
macro_rules! bodies {
    ($p:expr) => {
        Bodies {
            position: &$p.position,
            velocity: &$p.velocity,
            angular_velocity: &$p.angular_velocity,
            radius: &$p.radius,
            mass: &$p.mass,
        }
    };
}
pub(crate) use bodies;

/// What one contact contributed over a step, before it is booked: forces,
/// energies, and what the stability checks read. Pair and wall contacts both
/// produce one, and [`BlockBooks::add`](super::books::BlockBooks::add) checks and books
/// both the same way.
#[derive(Debug, Clone, Copy, Default)]
pub struct ContactResult {
    /// Force on particle `i` (N); particle `j` of a pair gets the opposite.
    pub force_i: DVec3,
    pub torque_i: DVec3,
    /// Torque on particle `j` of a pair (N m); unused for a wall.
    pub torque_j: DVec3,
    pub dissipated_normal_j: f64,
    pub dissipated_tangential_j: f64,
    pub stiffness_work_j: f64,
    pub integrator_j: f64,
    /// Change of the energy stored in the contact over the step (J).
    pub stored_change_j: f64,
    /// Overlap as a fraction of the smaller radius.
    pub overlap_ratio: f64,
    /// Normal approach speed now (m/s).
    pub approach_mps: f64,
    /// Steps the collision will take as the Hertz duration at its approach
    /// speed predicts, set when the contact opens (else infinite).
    pub steps_per_collision: f64,
    /// Steps the collision took, counted, set on the step it ends (the first
    /// step its overlap is gone) when its beginning was seen; else zero.
    pub counted_steps: u32,
    /// With `counted_steps`: the steps planned for it when it began.
    pub counted_planned_steps: f32,
    /// Normal approach speed when the contact opened this step (else zero).
    pub onset_speed_mps: f64,
}

/// Which contact a [`ContactResult`] belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContactAt {
    /// Particles `i < j`.
    Pair(usize, usize),
    /// Particle `i` and wall number `w`.
    Wall(usize, usize),
}

/// The particle state a contact reads, borrowed apart from the forces and
/// torques it writes.
#[derive(Clone, Copy)]
pub struct Bodies<'a> {
    pub position: &'a [DVec3],
    pub velocity: &'a [DVec3],
    pub angular_velocity: &'a [DVec3],
    pub radius: &'a [f64],
    pub mass: &'a [f64],
}

/// Where the walls are this step.
#[derive(Clone, Copy)]
pub struct WallGeometry<'a> {
    pub shapes: &'a [WallShape],
    pub offset: DVec3,
    pub v_wall: DVec3,
    /// The walls themselves, for the offset and velocity of a wall that
    /// moves on its own ([`Walls::offset_of`], [`Walls::velocity_of`]).
    pub walls: &'a Walls,
}

impl WallGeometry<'_> {
    /// True when some wall moves on its own.
    #[inline]
    pub fn moves_apart(&self) -> bool {
        !self.walls.own.is_empty()
    }
}

/// Which instance of the force loops a law needs: (damped, frictional).
pub fn law_kind(law: &ContactLaw) -> (bool, bool) {
    (
        matches!(law.damping, NormalDamping::Restitution { .. }),
        matches!(law.tangential, Tangential::MindlinCoulomb { .. }),
    )
}

/// Steps an opening collision will take, and its approach speed: the Hertz
/// duration (eq. 5.10) at the normal approach speed, when the contact opens
/// during a step of `dt` (else infinitely many steps and no onset speed).
#[inline]
pub fn onset(
    law: &ContactLaw,
    geometry: &ContactGeometry,
    dt: f64,
    state: &ContactState,
) -> (f64, f64) {
    if dt > 0.0 && state.delta_prev <= 0.0 {
        let v_n = geometry.v_rel.dot(geometry.normal).max(0.0);
        let t_c = hertz_theory::contact_duration_s(
            geometry.m_star_kg,
            law.e_star_pa,
            geometry.r_star_m,
            v_n,
        );
        (t_c / dt, v_n)
    } else {
        (f64::INFINITY, 0.0)
    }
}

/// Evaluates a touching contact and what the checks need: the contact
/// point's lever `arms` on bodies i and j (zero for a wall; unused without
/// friction), and the smaller radius the overlap is measured against. Always
/// inlined: the result is then written straight into the caller's slot
/// instead of being copied (a 10 % cost per step when it was not).
#[inline(always)]
pub fn resolve_contact<const D: bool, const F: bool>(
    law: &ContactLaw,
    geometry: &ContactGeometry,
    (arm_i, arm_j): (DVec3, DVec3),
    smaller_radius_m: f64,
    dt: f64,
    st: &mut ContactState,
) -> ContactResult {
    let (steps_per_collision, onset_speed_mps) = onset(law, geometry, dt, st);
    let (began, touched, planned) = (st.delta_prev <= 0.0, st.steps_touching, st.planned_steps);
    let out = evaluate_contact_with::<D, F>(law, geometry, dt, st);
    let counted_steps = count_steps(geometry.delta_m, dt, began, touched, st);
    if began && dt > 0.0 {
        st.planned_steps = steps_per_collision as f32;
    }
    let (torque_i, torque_j) = if F {
        (
            arm_i.cross(out.tangential_on_i),
            arm_j.cross(-out.tangential_on_i),
        )
    } else {
        (DVec3::ZERO, DVec3::ZERO)
    };
    ContactResult {
        force_i: out.force_on_i,
        torque_i,
        torque_j,
        dissipated_normal_j: out.dissipated_normal_j,
        dissipated_tangential_j: out.dissipated_tangential_j,
        stiffness_work_j: out.stiffness_work_j,
        integrator_j: out.integrator_j,
        stored_change_j: out.stored_change_j,
        overlap_ratio: geometry.delta_m / smaller_radius_m,
        approach_mps: geometry.v_rel.dot(geometry.normal),
        steps_per_collision,
        onset_speed_mps,
        counted_steps,
        counted_planned_steps: planned,
    }
}

/// Counts the steps of a collision: a contact that `began` this step (of
/// `dt` > 0) has touched for one step, one that touched `touched` steps
/// before and still touches (overlap `delta_m` > 0) for one more, unless its
/// count is zero (its beginning was not seen). Returns the count of a
/// contact that ended this step (its state already reset by the law), zero
/// for one that goes on or was not counted. A pure evaluation (`dt` = 0)
/// counts nothing.
#[inline(always)]
fn count_steps(delta_m: f64, dt: f64, began: bool, touched: u32, st: &mut ContactState) -> u32 {
    if delta_m <= 0.0 {
        return touched;
    }
    if dt > 0.0 {
        st.steps_touching = if began {
            1
        } else {
            touched.saturating_add(u32::from(touched > 0))
        };
    }
    0
}

/// One particle-wall contact (thesis Section 3.3: overlap eq. 3.12, normal eq.
/// 3.14; a flat wall, R* = R and m* = m). `dist` is the centre's distance to
/// the wall and `normal` points from the centre to the wall. Without
/// friction the spin is left out of the contact velocity: only its normal
/// part acts, and the spin has none. `shared`: the count of sub-sphere
/// contacts the particle's body shares with this wall, when they are shared.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn wall_contact<const D: bool, const F: bool>(
    law: &ContactLaw,
    b: &Bodies,
    i: usize,
    dist: f64,
    normal: DVec3,
    v_wall: DVec3,
    (dt, shared): (f64, Option<u32>),
    st: &mut ContactState,
) -> ContactResult {
    let r = b.radius[i];
    let delta = r - dist;
    let (arm, v_rel) = if F {
        let arm = normal * (r - 0.5 * delta.max(0.0));
        (
            arm,
            b.velocity[i] + b.angular_velocity[i].cross(arm) - v_wall,
        )
    } else {
        (DVec3::ZERO, b.velocity[i] - v_wall)
    };
    let geometry = ContactGeometry {
        r_star_m: r,
        m_star_kg: b.mass[i],
        delta_m: delta,
        normal,
        v_rel,
        share: shared.map_or(1.0, share_of),
    };
    let jump = reshare(law, &geometry, shared, dt, st);
    let mut out = resolve_contact::<D, F>(law, &geometry, (arm, DVec3::ZERO), r, dt, st);
    book_reshare(&mut out, jump);
    out
}

/// One particle-particle contact (thesis eq. 3.1–3.8, 3.26–3.27); `None`
/// when the particles are apart and were apart. `gap` is what the pair
/// list keeps of the previous step ([`NeighbourList::gaps`]: the overlap of
/// a touching pair, minus the squared distance of the centres of one
/// apart), read for the trapezoid at contact onset and updated here; `st`
/// is read only when they touch. `shared`: the count of sub-sphere contacts
/// the pair's bodies touch at, when they are shared.
///
/// [`NeighbourList::gaps`]: crate::dem::neighbours::NeighbourList::gaps
#[inline(always)]
pub fn pair_contact<const D: bool, const F: bool>(
    law: &ContactLaw,
    b: &Bodies,
    (i, j): (usize, usize),
    (dt, shared): (f64, Option<u32>),
    gap: &mut f64,
    st: &mut ContactState,
) -> Option<ContactResult> {
    let d = b.position[j] - b.position[i];
    let (ri, rj) = (b.radius[i], b.radius[j]);
    let dist_sq = d.length_squared();
    let reach = ri + rj;
    if dist_sq >= reach * reach && *gap <= 0.0 {
        // Most listed pairs, every step: no square root until one touches.
        *gap = -dist_sq;
        return None;
    }
    if *gap <= 0.0 {
        // Opening: the contact's books start from the gap.
        st.delta_prev = gap_from_code(reach, *gap);
    }
    let dist = dist_sq.sqrt();
    let n = d / dist;
    let delta = reach - dist;
    let (arms, v_rel) = if F {
        let half_overlap = 0.5 * delta.max(0.0);
        let arm_i = n * (ri - half_overlap);
        let arm_j = -n * (rj - half_overlap);
        let v_rel = b.velocity[i] + b.angular_velocity[i].cross(arm_i)
            - b.velocity[j]
            - b.angular_velocity[j].cross(arm_j);
        ((arm_i, arm_j), v_rel)
    } else {
        ((DVec3::ZERO, DVec3::ZERO), b.velocity[i] - b.velocity[j])
    };
    let geometry = ContactGeometry {
        r_star_m: effective_radius_m(ri, rj),
        m_star_kg: effective_mass_kg(b.mass[i], b.mass[j]),
        delta_m: delta,
        normal: n,
        v_rel,
        share: shared.map_or(1.0, share_of),
    };
    let jump = reshare(law, &geometry, shared, dt, st);
    let mut out = resolve_contact::<D, F>(law, &geometry, arms, ri.min(rj), dt, st);
    book_reshare(&mut out, jump);
    *gap = if delta > 0.0 { st.delta_prev } else { -dist_sq };
    Some(out)
}

/// The share of one contact that each of `n` shared contacts carries.
#[inline(always)]
pub fn share_of(n: u32) -> f64 {
    1.0 / f64::from(n.max(1))
}

/// A shared contact that touched at the previous step and touches now,
/// among `shared` contacts of its body pair this step where it was among
/// `n_prev` then: its normal spring's stored energy is rescaled by
/// `n_prev / n`, the stiffness it has now, at the middle of the step (the
/// overlap where velocity Verlet's trapezoid turns from the force at the
/// step's start to the one at its end; rescaled at the step's end instead,
/// a prolate pair's books lost up to 9e-3 of its dissipation to the
/// integrator rather than below 1e-6). Returns the energy that added (J;
/// negative: taken), which no force put in: the stiffness work of the
/// normal spring, booked as the tangential spring's is in the energy
/// balance of Terzioglu's thesis eq. 6.4. `n_prev` is read back from the
/// elastic force the contact carried, `f_el,prev = f_el(δ_prev) / n_prev`
/// (the contact state keeps no count; an integer ratio, rounded). Zero for
/// a whole contact, a pure evaluation, or a contact that opens or closes.
#[inline(always)]
fn reshare(
    law: &ContactLaw,
    geometry: &ContactGeometry,
    shared: Option<u32>,
    dt: f64,
    st: &mut ContactState,
) -> f64 {
    let Some(n) = shared else {
        return 0.0;
    };
    if dt <= 0.0 || geometry.delta_m <= 0.0 || st.delta_prev <= 0.0 || st.fel_prev <= 0.0 {
        return 0.0;
    }
    let whole_prev = law.hertz_force_n(geometry.r_star_m, st.delta_prev);
    let n_prev = (whole_prev / st.fel_prev).round();
    let n = f64::from(n.max(1));
    if n_prev == n {
        return 0.0;
    }
    // At the middle of the step, where the integrator's trapezoid (the
    // force at its start over its first half, at its end over the second)
    // changes from the old stiffness to the new.
    let u_mid = st.u_normal_j + 0.5 * st.fel_prev * (geometry.delta_m - st.delta_prev);
    let jump = u_mid * (n_prev / n - 1.0);
    st.u_normal_j += jump;
    jump
}

/// Books the normal spring's stiffness work of [`reshare`] in a contact's
/// result: stored, and taken from the net dissipation (as the tangential
/// spring's stiffness work is), so that what the contact took from the
/// motion is still what it stored plus what it dissipated.
#[inline(always)]
fn book_reshare(out: &mut ContactResult, jump: f64) {
    if jump != 0.0 {
        out.stiffness_work_j += jump;
        out.stored_change_j += jump;
        out.dissipated_normal_j -= jump;
    }
}

/// The gap (m, never positive) of a pair apart whose centres, `reach`
/// apart when they touch, were `sqrt(-code)` apart: `reach - sqrt(-code)`,
/// the very bits the step would have computed then. Zero for a pair the
/// list's rebuild found apart by a rounding step that the step's own test
/// (squared distances) finds touching: it opens now, from no gap.
#[inline(always)]
pub fn gap_from_code(reach_m: f64, code: f64) -> f64 {
    let gap = reach_m - (-code).sqrt();
    if gap > 0.0 { 0.0 } else { gap }
}
