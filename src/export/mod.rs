//! Exporters: a scene or a run written for another program. The LAMMPS input
//! deck of a scene and its settled bed (`lammps_deck`, its rigid bodies
//! `lammps_bodies`), ParaView dumps of a run
//! as VTK XML PolyData (`vtk_dump`) and the snapshot strip of a run (`snapshots`).

pub mod lammps_bodies;
pub mod lammps_deck;
pub mod snapshots;
pub mod vtk_dump;
