//! Every number a world's state and books hold, as bits: what the
//! determinism tests compare.

use vlab::dem::World;

/// Every number the state and the books hold, as bits.
pub fn fingerprint(w: &World) -> (Vec<u64>, String) {
    let p = &w.particles;
    let bits = [
        &p.position,
        &p.velocity,
        &p.angular_velocity,
        &p.force,
        &p.torque,
    ]
    .iter()
    .flat_map(|v| v.iter().flat_map(|x| x.to_array().map(f64::to_bits)))
    .collect();
    let books = format!(
        "{:?} {:?} {:?} {:?} {:?} {:?} {:?}",
        w.ledger,
        w.energy_state(),
        w.wall_force(),
        w.impact_speeds,
        w.planned_steps_per_contact,
        w.fewest_counted_steps_per_contact,
        w.fastest_collision
    );
    (bits, books)
}
