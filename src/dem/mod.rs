//! The discrete-element engine: spheres and rigid bodies of spheres in rigid
//! walls (thesis Chapters 3, 4 and 5).
//!
//! Pure state and physics, driven by the wall kinematics it is given: no rigs, no
//! sensors, no files. [`World`] holds the state and advances it with
//! [`World::step`], a pipeline of named stages (`step/`: integration, wall
//! drive, neighbour update, contact forces in blocks, books, checks);
//! [`contact`] holds the force laws as small pure functions; [`ledger`] keeps
//! the energy books; [`clumps`] and [`rigid_rotation`] make rigid bodies of
//! sub-spheres (the multi-sphere particles of thesis Chapter 4).

pub mod body_collision;
pub mod clumps;
pub mod contact;
pub mod error;
pub mod hertz_theory;
pub mod ledger;
pub mod material;
pub mod neighbours;
pub mod ordering;
pub mod orientation_order;
pub mod particles;
pub mod restitution;
pub mod rigid_rotation;
pub mod state_hash;
mod step;
pub mod testbed;
pub mod timestep;
pub mod walls;
pub mod world;

pub use contact::{ContactLaw, ContactParams, ContactState};
pub use error::DemError;
pub use ledger::{Dissipation, EnergyState, Ledger, LedgerBalance, LedgerSnapshot};
pub use material::Material;
pub use particles::Particles;
pub use restitution::RestitutionMode;
pub use step::isa;
pub use step::team::Team;
pub use step::thread_choice::TRIAL_STEPS;
pub use walls::{WallShape, Walls};
pub use world::{AUTO_PARALLEL_MIN_PAIRS, CollisionSteps, ImpactSpeeds, Numerics, World};
