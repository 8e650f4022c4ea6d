//! What the force transducer between shaker and enclosure reads (thesis
//! Section 7.4.2, Fig. 7.6-7.7; docs/design.md, "The rig").
//!
//! Axis: the drive axis, positive along the accelerometer's positive axis
//! (up, when the axis is vertical). Newton for the rigid enclosure of mass
//! `m_enc` above the gauge:
//!
//! `m_enc a = F_shaker + F_p - W`,
//!
//! where `F_p` is the axial force the particles exert on the enclosure and
//! `W = m_enc g` its weight when the axis is vertical (0 when horizontal). The
//! gauge reads the force the shaker applies to the enclosure,
//!
//! `F_shaker = m_enc a - F_p + W`.
//!
//! With this sign, `F_shaker * v` is the power flowing from the shaker into the
//! damper (enclosure + particles): the convention of
//! [`crate::signals::power`], where dissipated power reads positive. An empty
//! enclosure gives `F = m_enc a + W`, whose time-varying part takes no power.

/// The force the gauge reads, in N: `m_enc a - F_p + W` (see the module docs).
///
/// - `enclosure_mass_kg`: mass above the gauge, kg;
/// - `enclosure_accel_mps2`: enclosure acceleration along the axis, m/s^2;
/// - `particle_force_on_enclosure_n`: axial force of the particles on the
///   enclosure, N;
/// - `static_weight_n`: the enclosure's weight along the axis, `m_enc g` when the
///   axis is vertical, 0 when horizontal, N.
#[inline]
pub fn transducer_force_n(
    enclosure_mass_kg: f64,
    enclosure_accel_mps2: f64,
    particle_force_on_enclosure_n: f64,
    static_weight_n: f64,
) -> f64 {
    enclosure_mass_kg * enclosure_accel_mps2 - particle_force_on_enclosure_n + static_weight_n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn newton_for_the_enclosure() {
        // At rest on a vertical shaker with particles (weight 0.27 N) lying on
        // the base: the gauge carries enclosure and particles.
        let (m, g) = (0.25, 9.81);
        let particles_on_base = -0.0279 * g;
        let f = transducer_force_n(m, 0.0, particles_on_base, m * g);
        assert!((f - (m + 0.0279) * g).abs() < 1e-12);
        // Accelerating an empty horizontal enclosure needs exactly m a.
        assert_eq!(transducer_force_n(m, 100.0, 0.0, 0.0), 25.0);
    }

    #[test]
    fn power_into_a_dissipative_load_is_positive() {
        // Particles dragging on the enclosure oppose its velocity: F_p = -c v.
        let (c, v) = (3.0, 0.5);
        let f = transducer_force_n(0.25, 0.0, -c * v, 0.0);
        assert!(f * v > 0.0);
    }
}
