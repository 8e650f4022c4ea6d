//! Particle states for ParaView: VTK XML PolyData (`.vtp`) frames and `.pvd`
//! time series, written through the `vtkio` crate by a [`StepObserver`].
//!
//! Every `every_s` of drive time [`VtkDump`] writes two frames:
//! - `particles-NNNNN.vtp`: one vertex per particle at its centre, with point
//!   data `velocity` (m/s), `speed` (m/s), `spin` (angular velocity, rad/s),
//!   `radius` (m), `contact_count` (contacts now, particles and walls) and
//!   `dissipation_rate_w`: the energy the particle's contacts dissipated since
//!   the previous frame over the time between (W; a pair contact's energy is
//!   shared half and half; zero in the first frame, and throughout unless the
//!   world tracks it, [`crate::dem::World::track_particle_dissipation`]);
//! - `enclosure-NNNNN.vtp`: the closed cylinder as polygons (side wall and both
//!   end caps) at its current displacement.
//!
//! `particles.pvd` and `enclosure.pvd` list the frames with their times (from
//! the drive start, s). Coordinates are the DEM's: the enclosure axis is z;
//! gravity is −z (vertical) or −y (horizontal). In ParaView: open both `.pvd`
//! files, apply a Glyph filter (sphere, scale array `radius`, scale factor 2:
//! ParaView's unit sphere has radius 0.5) to the particles and colour by
//! `speed`. Every file is written atomically.

use std::f64::consts::PI;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use vtkio::model::{
    Attribute, Attributes, ByteOrder, DataSet, Piece, PolyDataPiece, Version, VertexNumbers, Vtk,
};

use crate::atomic_write::write_atomic;
use crate::dem::World;
use crate::experiment::damper::{Kinematics, StepObserver};

/// Segments of the drawn cylinder.
const SEGMENTS: usize = 32;

/// Errors of a dump.
#[derive(Debug, thiserror::Error)]
pub enum DumpError {
    #[error("cannot write {path}: {message}")]
    Write { path: PathBuf, message: String },
}

/// A [`StepObserver`] that writes VTK frames; see the module documentation.
#[derive(Debug)]
pub struct VtkDump {
    dir: PathBuf,
    every_s: f64,
    next_s: f64,
    radius_m: f64,
    length_m: f64,
    frames: Vec<(f64, String, String)>,
    last: Option<(f64, Vec<f64>)>,
    counts: Vec<u32>,
    error: Option<DumpError>,
}

impl VtkDump {
    /// Dumps into `dir` (which must exist) every `every_s` of drive time from
    /// `from_s` (drive time) on; the enclosure is a cylinder of `radius_m` and
    /// `length_m`.
    pub fn new(dir: &Path, every_s: f64, from_s: f64, radius_m: f64, length_m: f64) -> Self {
        VtkDump {
            dir: dir.to_path_buf(),
            every_s,
            next_s: from_s,
            radius_m,
            length_m,
            frames: Vec::new(),
            last: None,
            counts: Vec::new(),
            error: None,
        }
    }

    /// Writes the `.pvd` series and returns the files written (frames
    /// included), or the first error met while dumping.
    pub fn finish(self) -> Result<Vec<PathBuf>, DumpError> {
        if let Some(e) = self.error {
            return Err(e);
        }
        let mut files = Vec::new();
        for (name, pick) in [("particles.pvd", 0), ("enclosure.pvd", 1)] {
            let mut text = String::from(
                "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
            );
            for (t, p, e) in &self.frames {
                let file = if pick == 0 { p } else { e };
                text.push_str(&format!(
                    "    <DataSet timestep=\"{t}\" group=\"\" part=\"0\" file=\"{file}\"/>\n"
                ));
                if pick == 0 {
                    files.push(self.dir.join(p));
                    files.push(self.dir.join(e));
                }
            }
            text.push_str("  </Collection>\n</VTKFile>\n");
            let path = self.dir.join(name);
            write_atomic(&path, |w| w.write_all(text.as_bytes())).map_err(|e| {
                DumpError::Write {
                    path: path.clone(),
                    message: e.to_string(),
                }
            })?;
            files.push(path);
        }
        Ok(files)
    }

    fn frame(&mut self, t_s: f64, world: &World) -> Result<(), DumpError> {
        let k = self.frames.len();
        let pname = format!("particles-{k:05}.vtp");
        let ename = format!("enclosure-{k:05}.vtp");
        let p = &world.particles;
        let n = p.len();
        world.contacts_per_particle(&mut self.counts);
        let rate: Vec<f64> = match (world.particle_dissipation_j(), &self.last) {
            (Some(now), Some((t0, before))) if t_s > *t0 => now
                .iter()
                .zip(before)
                .map(|(a, b)| (a - b) / (t_s - t0))
                .collect(),
            _ => vec![0.0; n],
        };
        self.last = world.particle_dissipation_j().map(|d| (t_s, d.to_vec()));
        let flat =
            |v: &[glam::DVec3]| -> Vec<f64> { v.iter().flat_map(|x| x.to_array()).collect() };
        let piece = PolyDataPiece {
            points: flat(&p.position).into(),
            verts: Some(VertexNumbers::XML {
                connectivity: (0..n as u64).collect(),
                offsets: (1..=n as u64).collect(),
            }),
            lines: None,
            polys: None,
            strips: None,
            data: Attributes {
                point: vec![
                    Attribute::vectors("velocity").with_data(flat(&p.velocity)),
                    Attribute::scalars("speed", 1)
                        .with_data(p.velocity.iter().map(|v| v.length()).collect::<Vec<f64>>()),
                    Attribute::vectors("spin").with_data(flat(&p.angular_velocity)),
                    Attribute::scalars("radius", 1).with_data(p.radius.clone()),
                    Attribute::scalars("contact_count", 1).with_data(self.counts.clone()),
                    Attribute::scalars("dissipation_rate_w", 1).with_data(rate),
                ],
                cell: Vec::new(),
            },
        };
        self.write_vtp(&pname, piece, &format!("vlab particles t = {t_s} s"))?;
        let enclosure = self.enclosure(world.walls.displacement_m);
        self.write_vtp(&ename, enclosure, &format!("vlab enclosure t = {t_s} s"))?;
        self.frames.push((t_s, pname, ename));
        Ok(())
    }

    /// The closed cylinder at axial displacement `u`: a ring of quads and two
    /// polygon caps.
    fn enclosure(&self, u: f64) -> PolyDataPiece {
        let mut points = Vec::with_capacity(6 * SEGMENTS);
        for z in [u, u + self.length_m] {
            for s in 0..SEGMENTS {
                let a = 2.0 * PI * s as f64 / SEGMENTS as f64;
                points.extend([self.radius_m * a.cos(), self.radius_m * a.sin(), z]);
            }
        }
        let m = SEGMENTS as u64;
        let mut connectivity = Vec::new();
        let mut offsets = Vec::new();
        for s in 0..m {
            let t = (s + 1) % m;
            connectivity.extend([s, t, m + t, m + s]);
            offsets.push(connectivity.len() as u64);
        }
        connectivity.extend(0..m);
        offsets.push(connectivity.len() as u64);
        connectivity.extend(m..2 * m);
        offsets.push(connectivity.len() as u64);
        PolyDataPiece {
            points: points.into(),
            verts: None,
            lines: None,
            polys: Some(VertexNumbers::XML {
                connectivity,
                offsets,
            }),
            strips: None,
            data: Attributes::new(),
        }
    }

    fn write_vtp(&self, name: &str, piece: PolyDataPiece, title: &str) -> Result<(), DumpError> {
        let path = self.dir.join(name);
        let vtk = Vtk {
            version: Version::new((1, 0)),
            title: title.to_string(),
            byte_order: ByteOrder::LittleEndian,
            file_path: None,
            data: DataSet::PolyData {
                meta: None,
                pieces: vec![Piece::Inline(Box::new(piece))],
            },
        };
        let mut bytes = Vec::new();
        vtk.write_xml(&mut bytes).map_err(|e| DumpError::Write {
            path: path.clone(),
            message: e.to_string(),
        })?;
        write_atomic(&path, |w| w.write_all(&bytes)).map_err(|e| DumpError::Write {
            path,
            message: e.to_string(),
        })
    }
}

impl StepObserver for VtkDump {
    fn observe(&mut self, t_s: f64, world: &World, _enclosure: &Kinematics) {
        if self.error.is_some() || t_s + 1e-12 < self.next_s {
            return;
        }
        self.next_s += self.every_s;
        if let Err(e) = self.frame(t_s, world) {
            self.error = Some(e);
        }
    }

    /// The frames colour each particle by the energy its contacts dissipated.
    fn wants_particle_dissipation(&self) -> bool {
        true
    }
}
