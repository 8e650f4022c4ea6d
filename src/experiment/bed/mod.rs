//! A bed of particles ready to drive: poured into its enclosure as a loose
//! column (`fill`), settled under gravity with the settling law of
//! Terzioglu's thesis, Section 6.2.2 (`settle`), and kept between runs so
//! that settling is paid once per scene and seed (`cache`).

pub mod cache;
pub mod fill;
pub mod settle;
