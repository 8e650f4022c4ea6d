//! Time integration: velocity Verlet (kick–drift–kick) for spheres with six
//! degrees of freedom.
//!
//! Newton's and Euler's equations for each sphere (eq. 3.23–3.24 of
//! Terzioglu's thesis; for a sphere the gyroscopic terms vanish, so
//! `m a = F` and `I ω̇ = τ` with the resultant loads of eq. 3.25–3.26) are
//! integrated by velocity Verlet, which is symplectic, unlike the explicit
//! Euler of eq. 3.29–3.30 (whose angle update, eq. 3.30, should use ω, not
//! its derivative). The orientation itself is not tracked: nothing in the
//! contact laws reads it.
//!
//! The seam: [`VelocityVerlet::kick_drift`] runs before the forces (half
//! kick `v += F/m Δt/2`, `ω += τ/I Δt/2`, drift `x += v Δt`) and
//! [`VelocityVerlet::kick`] after them (the second half kick). Another
//! integrator replaces this struct by one that offers the same two calls;
//! both are plain loops over fixed blocks of particles ([`PARTICLE_BLOCK`]),
//! on one core or on all threads, with the same bits either way.
//!
//! Each pass also sums the power of the contact forces (gravity taken out)
//! on the half-step velocities, which [`super::books::close_step`] needs: the
//! trapezoid of the forces at both ends of the step on the drift.
//!
//! The second half kick first adds, block by block, the shares of the pairs
//! that crossed into the block ([`CrossShares`]), which the force stage left
//! for it: one pass over the particles instead of two.

use super::block_size::PARTICLE_BLOCK;
use super::blocks::CrossShares;
use super::isa;
use super::team::{Team, for_each_block};
use crate::dem::clumps::NOT_IN_CLUMP;
use crate::dem::neighbours::NeighbourList;
use crate::dem::particles::Particles;
use glam::DVec3;

/// Velocity Verlet for a time step `dt_s` under `gravity`.
#[derive(Debug, Clone, Copy)]
pub struct VelocityVerlet {
    /// Time step (s).
    pub dt_s: f64,
    /// Gravitational acceleration (m/s²).
    pub gravity: DVec3,
    /// Integrate the spin too (some law has friction; without friction
    /// nothing could change it).
    pub rotation: bool,
}

impl VelocityVerlet {
    /// The first half of the step: half kick and drift of every particle.
    /// Returns the power `(F - m g)·v + τ·ω` summed over the particles, the
    /// first particle whose position is not finite, and whether some
    /// particle drifted more than half the skin from where `list` was built
    /// (a list built for other particles must be rebuilt anyway).
    pub fn kick_drift(
        &self,
        particles: &mut Particles,
        list: &NeighbourList,
        sums: &mut Vec<KickSums>,
        team: Option<&mut Team>,
    ) -> KickSums {
        let reference = list.reference();
        let reference = (reference.len() == particles.len()).then_some(reference);
        let kick = self.pass(Pass::KickDrift, list.rebuild_travel_sq_m2());
        half_kick(&kick, particles, (reference, None), sums, 0.0, team)
    }

    /// The second half kick of every particle, with the forces at the new
    /// positions, once each block has added the `shares` of the pairs that
    /// crossed into it. Returns `carry` plus the power `(F - m g)·v + τ·ω`
    /// summed over the particles, before the kick.
    pub fn kick(
        &self,
        particles: &mut Particles,
        shares: Option<CrossShares>,
        sums: &mut Vec<KickSums>,
        carry: f64,
        team: Option<&mut Team>,
    ) -> KickSums {
        let kick = self.pass(Pass::Kick, f64::INFINITY);
        half_kick(&kick, particles, (None, shares), sums, carry, team)
    }

    fn pass(&self, pass: Pass, travel_sq_m2: f64) -> Kick {
        Kick {
            pass,
            dt: self.dt_s,
            gravity: self.gravity,
            rotation: self.rotation,
            travel_sq_m2,
        }
    }
}

/// Which half of velocity Verlet a particle pass is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Pass {
    /// Half kick, then drift; the power is read after the drift.
    KickDrift,
    /// The power is read, then the second half kick.
    Kick,
}

/// One particle pass of velocity Verlet.
#[derive(Debug, Clone, Copy)]
struct Kick {
    pass: Pass,
    dt: f64,
    gravity: DVec3,
    /// Integrate the spin too (some law has friction).
    rotation: bool,
    /// Squared travel from where the pair list was built beyond which it
    /// must be rebuilt (m²).
    travel_sq_m2: f64,
}

/// What a half kick found, over a block or over all particles.
#[derive(Debug, Clone, Copy, Default)]
pub struct KickSums {
    /// `carry` plus the contact power `(F - m g)·v + τ·ω`, summed in order.
    pub work: f64,
    /// The first particle whose position is not finite (drift only).
    pub nonfinite: Option<usize>,
    /// Some particle travelled more than half the skin since the pair list
    /// was built (drift only).
    pub moved_far: bool,
}

/// The loads and inertia of a block of particles.
struct Loads<'a> {
    force: &'a mut [DVec3],
    torque: &'a mut [DVec3],
    mass: &'a [f64],
    inv_mass: &'a [f64],
    inv_inertia: &'a [f64],
}

impl Kick {
    /// The pass over one block of positions `x`, velocities `v` and spins `w`
    /// (`built_at`: where the pair list was built for them), leaving alone
    /// the sub-spheres of bodies (`clump`, read only when `CLUMPS`; their
    /// bodies move them, [`super::clump_motion`]): returns `carry`
    /// plus the contact power `(F - m g)·v + τ·ω` summed over the block in
    /// order, and on the first pass the first particle of the block whose
    /// position is not finite and whether one drifted far enough to need a
    /// new pair list.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn block<const CLUMPS: bool>(
        &self,
        l: &Loads,
        x: &mut [DVec3],
        v: &mut [DVec3],
        w: &mut [DVec3],
        clump: &[u32],
        built_at: Option<&[DVec3]>,
        carry: f64,
    ) -> KickSums {
        // The pass and the spin chosen once for the block's loop, not per
        // particle inside it.
        match (self.pass, self.rotation) {
            (Pass::KickDrift, true) => {
                self.block_of::<CLUMPS, true, true>(l, x, v, w, clump, built_at, carry)
            }
            (Pass::KickDrift, false) => {
                self.block_of::<CLUMPS, true, false>(l, x, v, w, clump, built_at, carry)
            }
            (Pass::Kick, true) => {
                self.block_of::<CLUMPS, false, true>(l, x, v, w, clump, built_at, carry)
            }
            (Pass::Kick, false) => {
                self.block_of::<CLUMPS, false, false>(l, x, v, w, clump, built_at, carry)
            }
        }
    }

    /// [`Self::block`] for the first pass (`DRIFT`) or the second, with
    /// the spin (`SPIN`) or without.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn block_of<const CLUMPS: bool, const DRIFT: bool, const SPIN: bool>(
        &self,
        l: &Loads,
        x: &mut [DVec3],
        v: &mut [DVec3],
        w: &mut [DVec3],
        clump: &[u32],
        built_at: Option<&[DVec3]>,
        carry: f64,
    ) -> KickSums {
        let half = 0.5 * self.dt;
        let g = self.gravity;
        let mut work = carry;
        for k in 0..x.len() {
            if CLUMPS && clump[k] != NOT_IN_CLUMP {
                continue;
            }
            let contact = l.force[k] - g * l.mass[k];
            if DRIFT {
                v[k] += l.force[k] * (l.inv_mass[k] * half);
                x[k] += v[k] * self.dt;
                if SPIN {
                    w[k] += l.torque[k] * (l.inv_inertia[k] * half);
                    work += contact.dot(v[k]) + l.torque[k].dot(w[k]);
                } else {
                    work += contact.dot(v[k]);
                }
            } else {
                if SPIN {
                    work += contact.dot(v[k]) + l.torque[k].dot(w[k]);
                    w[k] += l.torque[k] * (l.inv_inertia[k] * half);
                } else {
                    work += contact.dot(v[k]);
                }
                v[k] += l.force[k] * (l.inv_mass[k] * half);
            }
        }
        let (nonfinite, moved_far) = match (DRIFT, built_at) {
            (false, _) => (None, false),
            (true, built_at) => (
                x.iter().position(|p| !p.is_finite()),
                built_at.is_some_and(|r| {
                    x.iter()
                        .zip(r)
                        .any(|(p, q)| (*p - *q).length_squared() > self.travel_sq_m2)
                }),
            ),
        };
        KickSums {
            work,
            nonfinite,
            moved_far,
        }
    }
}

/// One half kick of every particle (and the drift, on the first pass),
/// in fixed blocks, whose sums go to `sums`. Returns the sum of the contact
/// power terms `(F - m g)·v + τ·ω` over the particles, added to `carry` in
/// particle order (block by block, so the same for any thread count; for
/// one block the order of a plain loop), the first particle whose position
/// is not finite, and whether some particle drifted far enough from
/// `reference`, where the pair list was built, for the list to be rebuilt.
/// Each block first adds its `shares` of the pairs from earlier blocks.
fn half_kick(
    kick: &Kick,
    p: &mut Particles,
    (reference, shares): (Option<&[DVec3]>, Option<CrossShares>),
    sums: &mut Vec<KickSums>,
    carry: f64,
    team: Option<&mut Team>,
) -> KickSums {
    let (mass, inv_mass, inv_inertia) = (&p.mass, &p.inv_mass, &p.inv_inertia);
    let clump = &p.clump;
    let has_clumps = !p.clumps.is_empty();
    type Block<'b> = (
        (usize, &'b mut KickSums),
        (
            ((&'b mut [DVec3], &'b mut [DVec3]), &'b mut [DVec3]),
            (&'b mut [DVec3], &'b mut [DVec3]),
        ),
    );
    let block = |((c, out), (((x, v), w), (force, torque))): Block<'_>| {
        isa::run(
            #[inline(always)]
            || {
                let s = c * PARTICLE_BLOCK;
                let e = s + x.len();
                if let Some(shares) = &shares {
                    shares.add_to(s, force, torque);
                }
                let loads = Loads {
                    force,
                    torque,
                    mass: &mass[s..e],
                    inv_mass: &inv_mass[s..e],
                    inv_inertia: &inv_inertia[s..e],
                };
                let built_at = reference.map(|r| &r[s..e]);
                let carry = if c == 0 { carry } else { 0.0 };
                let sums = if has_clumps {
                    kick.block::<true>(&loads, x, v, w, &clump[s..e], built_at, carry)
                } else {
                    kick.block::<false>(&loads, x, v, w, &[], built_at, carry)
                };
                *out = KickSums {
                    nonfinite: sums.nonfinite.map(|k| s + k),
                    ..sums
                };
            },
        )
    };
    sums.clear();
    sums.resize(p.len().div_ceil(PARTICLE_BLOCK), KickSums::default());
    let blocks = sums.iter_mut().enumerate().zip(
        p.position
            .chunks_mut(PARTICLE_BLOCK)
            .zip(p.velocity.chunks_mut(PARTICLE_BLOCK))
            .zip(p.angular_velocity.chunks_mut(PARTICLE_BLOCK))
            .zip(
                p.force
                    .chunks_mut(PARTICLE_BLOCK)
                    .zip(p.torque.chunks_mut(PARTICLE_BLOCK)),
            ),
    );
    for_each_block(team, blocks, block);
    let mut total = KickSums {
        work: if sums.is_empty() { carry } else { 0.0 },
        nonfinite: None,
        moved_far: false,
    };
    for b in sums.iter() {
        total.work += b.work;
        total.nonfinite = total.nonfinite.or(b.nonfinite);
        total.moved_far |= b.moved_far;
    }
    total
}
