//! Packing fractions of equal spheres, the limits a damper's fill is held
//! against (thesis Section 6.4.1 and Table 6.3: the "CP" and "LP" rows).

/// Random close packing of equal spheres: the densest fill a random packing
/// reaches, and ν_max of the thesis' CP estimate of the bouncing-bed onset.
pub const CLOSE_PACKING: f64 = 0.64;
/// Random loose packing: ν_max of the thesis' LP estimate.
pub const LOOSE_PACKING: f64 = 0.55;
/// Densest fill a scene may ask for: random close packing.
pub const MAX_FILL: f64 = CLOSE_PACKING;
