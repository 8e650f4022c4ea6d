//! Particle states for ParaView: VTK XML PolyData (`.vtp`) frames and `.pvd`
//! time series, written by a [`StepObserver`].
//!
//! Every `every_s` of drive time [`VtkDump`] writes two frames:
//! - `particles-NNNNN.vtp`: one vertex per particle at its centre, with point
//!   data `velocity` (m/s), `speed` (m/s), `spin` (angular velocity, rad/s),
//!   `radius` (m), `contact_count` (contacts now, particles and walls) and
//!   `dissipation_rate_w`: the energy the particle's contacts dissipated since
//!   the previous frame over the time between (W; a pair contact's energy is
//!   shared half and half; zero in the first frame, and throughout unless the
//!   world tracks it, [`crate::dem::World::track_particle_dissipation`]);
//!   with rigid multi-sphere bodies, also `body` (the body each sub-sphere
//!   belongs to, 4294967295 for a free sphere) and `body_x_axis`,
//!   `body_z_axis` (its body's principal axes in space: a prolate's long
//!   axis is x, a torus's axis z), so that ParaView can colour by body or
//!   draw the axes as glyphs, `body_orientation` (its body's unit
//!   quaternion, body frame to space, as x, y, z, w) and `body_order_p2`
//!   (P₂ of its body's symmetry axis against the cylinder's axis, whose
//!   mean over the bodies is the order parameter of
//!   [`crate::dem::orientation_order`]; NaN for a body without one);
//! - `enclosure-NNNNN.vtp`: the closed cylinder as polygons (side wall and both
//!   end caps) at its current displacement.
//!
//! `particles.pvd` and `enclosure.pvd` list the frames with their times (from
//! the drive start, s). Coordinates are the DEM's: the enclosure axis is z;
//! gravity is −z (vertical) or −y (horizontal). In ParaView: open both `.pvd`
//! files, apply a Glyph filter (sphere, scale array `radius`, scale factor 2:
//! ParaView's unit sphere has radius 0.5) to the particles and colour by
//! `speed`. Every file is written atomically.
//!
//! # The file format, and why it is written here
//!
//! Each `.vtp` is VTK's XML PolyData, version 1.0, little-endian, with
//! `header_type="UInt64"`: one `<Piece>` with its `<PointData>` arrays (the
//! first scalar `speed` and the first vector `velocity` named as the
//! defaults), an empty `<CellData/>`, `<Points>`, and `<Verts>` (particles)
//! or `<Polys>` (enclosure) as `connectivity` and `offsets`. Every array is
//! inline `format="binary"`: base64 of an 8-byte little-endian byte count
//! followed by the values in little-endian order, count and values encoded
//! as one block. The bytes are those the `vtkio` 0.6 crate wrote before
//! (compared file by file on a `vlab shake --dump vtk` run).
//!
//! The file is written with `quick-xml` (elements, attributes, escaping) and
//! a base64 encoder of a few lines; [`read_vtp`] reads one back the same way,
//! for tests and tools. `vtkio` 0.6 pulled in `nom` 3 and `quick-xml` 0.22,
//! which the compiler warns a future Rust will reject; its 0.7 exists only
//! as a release candidate, and a library that models every VTK dataset is
//! more than two fixed PolyData layouts need. `quick-xml` is held at 0.41:
//! 0.42 needs Rust 1.86, above this crate's `rust-version`.

use std::borrow::Cow;
use std::f64::consts::PI;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use quick_xml::Writer;
use quick_xml::events::{BytesEnd, BytesStart, BytesText, Event};

use crate::atomic_write::write_atomic;
use crate::dem::clumps::NOT_IN_CLUMP;
use crate::dem::orientation_order::{CYLINDER_AXIS, legendre_p2, symmetry_axis};
use crate::dem::{Particles, World};
use crate::experiment::damper::{Kinematics, StepObserver};
use crate::validation::InvalidParameter;

/// Segments of the drawn cylinder.
const SEGMENTS: usize = 32;

/// Errors of a dump.
#[derive(Debug, thiserror::Error)]
pub enum DumpError {
    #[error("cannot write {path}: {message}")]
    Write { path: PathBuf, message: String },
    #[error("cannot read {path}: {message}")]
    Read { path: PathBuf, message: String },
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

/// Frames a drive cycle may be dumped in at most: a frame is a file of the
/// whole bed, and 1000 a cycle is far finer than a contact a viewer can see.
pub const MOST_FRAMES_A_CYCLE: f64 = 1000.0;

impl VtkDump {
    /// Checks a dump interval `every_s` against the drive's `period_s`:
    /// positive, and at most [`MOST_FRAMES_A_CYCLE`] frames a cycle (an
    /// interval of 1e-12 s wrote a file every step and a run never ended).
    pub fn check_every(every_s: f64, period_s: f64) -> Result<(), InvalidParameter> {
        let least_s = period_s / MOST_FRAMES_A_CYCLE;
        if every_s >= least_s && every_s.is_finite() {
            return Ok(());
        }
        Err(InvalidParameter::new(
            "every_s",
            every_s,
            "s",
            format!(
                "finite and at least a thousandth of the drive's period, {least_s:.3e} s (at most {MOST_FRAMES_A_CYCLE} frames a cycle, each a file of the whole bed)"
            ),
        ))
    }

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
        let p = world.particles.by_id();
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
        let speed: Vec<f64> = p.velocity.iter().map(|v| v.length()).collect();
        let velocity = flat(&p.velocity);
        let spin = flat(&p.angular_velocity);
        let points = flat(&p.position);
        let connectivity: Vec<u64> = (0..n as u64).collect();
        let offsets: Vec<u64> = (1..=n as u64).collect();
        let bodies = BodyArrays::of(&p);
        let mut point_data = vec![
            DataArray::named("velocity", 3, Values::F64(&velocity)),
            DataArray::named("speed", 1, Values::F64(&speed)),
            DataArray::named("spin", 3, Values::F64(&spin)),
            DataArray::named("radius", 1, Values::F64(&p.radius)),
            DataArray::named("contact_count", 1, Values::U32(&self.counts)),
            DataArray::named("dissipation_rate_w", 1, Values::F64(&rate)),
        ];
        if let Some(b) = &bodies {
            point_data.extend([
                DataArray::named("body", 1, Values::U32(&p.clump)),
                DataArray::named("body_x_axis", 3, Values::F64(&b.x_axis)),
                DataArray::named("body_z_axis", 3, Values::F64(&b.z_axis)),
                DataArray::named("body_orientation", 4, Values::F64(&b.orientation)),
                DataArray::named("body_order_p2", 1, Values::F64(&b.order_p2)),
            ]);
        }
        let piece = Piece {
            points: &points,
            point_data,
            cells: Cells::Verts,
            connectivity: &connectivity,
            offsets: &offsets,
        };
        self.write_vtp(&pname, &piece)?;
        let (points, connectivity, offsets) = self.enclosure(world.walls.displacement_m);
        let enclosure = Piece {
            points: &points,
            point_data: Vec::new(),
            cells: Cells::Polys,
            connectivity: &connectivity,
            offsets: &offsets,
        };
        self.write_vtp(&ename, &enclosure)?;
        self.frames.push((t_s, pname, ename));
        Ok(())
    }

    /// The closed cylinder at axial displacement `u`: a ring of quads and two
    /// polygon caps, as points, connectivity and offsets.
    fn enclosure(&self, u: f64) -> (Vec<f64>, Vec<u64>, Vec<u64>) {
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
        (points, connectivity, offsets)
    }

    fn write_vtp(&self, name: &str, piece: &Piece) -> Result<(), DumpError> {
        let path = self.dir.join(name);
        let bytes = piece.to_xml();
        write_atomic(&path, |w| w.write_all(&bytes)).map_err(|e| DumpError::Write {
            path,
            message: e.to_string(),
        })
    }
}

/// The values of a data array.
#[derive(Debug, Clone, Copy)]
enum Values<'a> {
    F64(&'a [f64]),
    U32(&'a [u32]),
    U64(&'a [u64]),
}

impl Values<'_> {
    /// VTK's name of the type.
    fn vtk_type(&self) -> &'static str {
        match self {
            Values::F64(_) => "Float64",
            Values::U32(_) => "UInt32",
            Values::U64(_) => "UInt64",
        }
    }

    /// The values as little-endian bytes.
    fn le_bytes(&self) -> Vec<u8> {
        match self {
            Values::F64(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            Values::U32(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            Values::U64(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        }
    }
}

/// Per sub-sphere of a rigid body, its body's principal x and z axes in
/// space (flattened): a prolate's long axis is x, a torus's axis z, so
/// ParaView can draw them as glyphs; `None` for spheres only.
struct BodyArrays {
    x_axis: Vec<f64>,
    z_axis: Vec<f64>,
    /// The body's quaternion (x, y, z, w); zero for a free sphere.
    orientation: Vec<f64>,
    /// P₂ of the body's symmetry axis against the cylinder's axis.
    order_p2: Vec<f64>,
}

impl BodyArrays {
    fn of(p: &Particles) -> Option<BodyArrays> {
        if p.clumps.is_empty() {
            return None;
        }
        let axis = |k: usize, e: glam::DVec3| match p.clump[k] {
            NOT_IN_CLUMP => glam::DVec3::ZERO,
            b => p.clumps.orientation[b as usize] * e,
        };
        let flat = |e: glam::DVec3| -> Vec<f64> {
            (0..p.len()).flat_map(|k| axis(k, e).to_array()).collect()
        };
        let body = |k: usize| (p.clump[k] != NOT_IN_CLUMP).then(|| p.clump[k] as usize);
        let orientation = (0..p.len())
            .flat_map(|k| body(k).map_or([0.0; 4], |b| p.clumps.orientation[b].to_array()))
            .collect();
        let order_p2 = (0..p.len())
            .map(|k| {
                let b = body(k)?;
                let axis = symmetry_axis(p.clumps.inertia[b])?;
                Some(legendre_p2(p.clumps.orientation[b] * axis, CYLINDER_AXIS))
            })
            .map(|v| v.unwrap_or(f64::NAN))
            .collect();
        Some(BodyArrays {
            x_axis: flat(glam::DVec3::X),
            z_axis: flat(glam::DVec3::Z),
            orientation,
            order_p2,
        })
    }
}

/// One `<DataArray>`.
#[derive(Debug, Clone, Copy)]
struct DataArray<'a> {
    name: Option<&'a str>,
    components: usize,
    values: Values<'a>,
}

impl<'a> DataArray<'a> {
    fn named(name: &'a str, components: usize, values: Values<'a>) -> Self {
        DataArray {
            name: Some(name),
            components,
            values,
        }
    }

    /// The element: attributes `type`, `Name`, `format`,
    /// `NumberOfComponents`, and the base64 of the byte count and the bytes.
    fn write(&self, w: &mut Writer<Vec<u8>>) {
        let components = self.components.to_string();
        let mut start = BytesStart::new("DataArray");
        start.push_attribute(("type", self.values.vtk_type()));
        if let Some(name) = self.name {
            start.push_attribute(("Name", name));
        }
        start.push_attribute(("format", "binary"));
        start.push_attribute(("NumberOfComponents", components.as_str()));
        let bytes = self.values.le_bytes();
        let mut block = (bytes.len() as u64).to_le_bytes().to_vec();
        block.extend_from_slice(&bytes);
        let text = base64_encode(&block);
        element(w, start, |w| event(w, Event::Text(BytesText::new(&text))));
    }
}

/// Which cells a piece's connectivity describes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Cells {
    /// One vertex per cell (`<Verts>`).
    Verts,
    /// Polygons (`<Polys>`).
    Polys,
}

/// One PolyData piece: points, point data and one kind of cell.
struct Piece<'a> {
    points: &'a [f64],
    point_data: Vec<DataArray<'a>>,
    cells: Cells,
    connectivity: &'a [u64],
    offsets: &'a [u64],
}

impl Piece<'_> {
    /// The whole `.vtp` file (see the module docs for the layout).
    fn to_xml(&self) -> Vec<u8> {
        let mut w = Writer::new(Vec::new());
        let file = BytesStart::new("VTKFile").with_attributes([
            ("type", "PolyData"),
            ("version", "1.0"),
            ("byte_order", "LittleEndian"),
            ("header_type", "UInt64"),
        ]);
        element(&mut w, file, |w| {
            element(w, BytesStart::new("PolyData"), |w| self.write_piece(w))
        });
        w.into_inner()
    }

    fn write_piece(&self, w: &mut Writer<Vec<u8>>) {
        let n_points = (self.points.len() / 3).to_string();
        let n_cells = self.offsets.len().to_string();
        let (verts, polys) = match self.cells {
            Cells::Verts => (n_cells.as_str(), "0"),
            Cells::Polys => ("0", n_cells.as_str()),
        };
        let piece = BytesStart::new("Piece").with_attributes([
            ("NumberOfPoints", n_points.as_str()),
            ("NumberOfLines", "0"),
            ("NumberOfStrips", "0"),
            ("NumberOfPolys", polys),
            ("NumberOfVerts", verts),
        ]);
        element(w, piece, |w| {
            if self.point_data.is_empty() {
                event(w, Event::Empty(BytesStart::new("PointData")));
            } else {
                let data = BytesStart::new("PointData")
                    .with_attributes([("Scalars", "speed"), ("Vectors", "velocity")]);
                element(w, data, |w| {
                    for a in &self.point_data {
                        a.write(w);
                    }
                });
            }
            event(w, Event::Empty(BytesStart::new("CellData")));
            element(w, BytesStart::new("Points"), |w| {
                DataArray {
                    name: None,
                    components: 3,
                    values: Values::F64(self.points),
                }
                .write(w)
            });
            let cells = match self.cells {
                Cells::Verts => "Verts",
                Cells::Polys => "Polys",
            };
            element(w, BytesStart::new(cells), |w| {
                DataArray::named("connectivity", 1, Values::U64(self.connectivity)).write(w);
                DataArray::named("offsets", 1, Values::U64(self.offsets)).write(w);
            });
        });
    }
}

/// Writes `start`, what `inner` writes, and the matching end tag.
fn element(w: &mut Writer<Vec<u8>>, start: BytesStart, inner: impl FnOnce(&mut Writer<Vec<u8>>)) {
    let end = BytesEnd::new(String::from_utf8_lossy(start.name().as_ref()).into_owned());
    event(w, Event::Start(start));
    inner(w);
    event(w, Event::End(end));
}

/// Writes one event into memory, which cannot fail.
fn event(w: &mut Writer<Vec<u8>>, e: Event) {
    // A `Vec<u8>` takes every write; the result is `Ok` by construction.
    let _ = w.write_event(e);
}

const BASE64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/// Standard base64 (RFC 4648, with `=` padding), as VTK's binary arrays use.
fn base64_encode(bytes: &[u8]) -> String {
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(BASE64[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// Decodes standard base64; `None` for text that is not.
fn base64_decode(text: &str) -> Option<Vec<u8>> {
    let text = text.trim();
    if text.len() % 4 != 0 {
        return None;
    }
    let mut out = Vec::with_capacity(text.len() / 4 * 3);
    let chunks = text.len() / 4;
    for (k, chunk) in text.as_bytes().chunks(4).enumerate() {
        let pad = chunk.iter().rev().take_while(|&&c| c == b'=').count();
        if pad > 2 || (pad > 0 && k + 1 != chunks) {
            return None;
        }
        let mut n = 0u32;
        for (i, &c) in chunk.iter().enumerate() {
            // `=` only as the padding at the very end.
            let v = match c {
                b'=' if i >= 4 - pad => 0,
                c => BASE64.iter().position(|&b| b == c)? as u32,
            };
            n = (n << 6) | v;
        }
        let bytes = n.to_be_bytes();
        out.extend_from_slice(&bytes[1..4 - pad]);
    }
    Some(out)
}

/// A `.vtp` file read back ([`read_vtp`]): its point count and its arrays.
#[derive(Debug, Clone, PartialEq)]
pub struct VtpFile {
    /// `NumberOfPoints` of the piece.
    pub n_points: usize,
    /// Every `<DataArray>` in file order.
    pub arrays: Vec<VtpArray>,
}

/// One data array of a [`VtpFile`].
#[derive(Debug, Clone, PartialEq)]
pub struct VtpArray {
    /// The element it stands in: `PointData`, `Points`, `Verts`, `Polys`.
    pub section: String,
    /// Its `Name` (empty for the points).
    pub name: String,
    /// Its VTK type (`Float64`, `UInt32`, `UInt64`).
    pub vtk_type: String,
    /// `NumberOfComponents`.
    pub components: usize,
    /// The values, converted to `f64` (exact for the counts and indices a
    /// dump holds).
    pub values: Vec<f64>,
}

impl VtpFile {
    /// The point-data array called `name`.
    pub fn point_data(&self, name: &str) -> Option<&VtpArray> {
        self.arrays
            .iter()
            .find(|a| a.section == "PointData" && a.name == name)
    }
}

/// Reads a `.vtp` file written by [`VtkDump`] (inline binary arrays with a
/// `UInt64` header, little-endian), checking each array's byte count.
pub fn read_vtp(path: &Path) -> Result<VtpFile, DumpError> {
    let fail = |message: String| DumpError::Read {
        path: path.to_path_buf(),
        message,
    };
    let text = std::fs::read_to_string(path).map_err(|e| fail(e.to_string()))?;
    parse_vtp(&text).map_err(fail)
}

/// [`read_vtp`] on the file's text.
fn parse_vtp(text: &str) -> Result<VtpFile, String> {
    let mut reader = quick_xml::Reader::from_str(text);
    let mut file = VtpFile {
        n_points: 0,
        arrays: Vec::new(),
    };
    let mut section = String::new();
    let mut open: Option<VtpArray> = None;
    loop {
        match reader.read_event().map_err(|e| e.to_string())? {
            Event::Start(e) => {
                let tag = String::from_utf8_lossy(e.name().as_ref()).into_owned();
                let attr = |key: &str| -> Option<String> {
                    e.attributes()
                        .flatten()
                        .find(|a| a.key.as_ref() == key.as_bytes())
                        .map(|a| String::from_utf8_lossy(&a.value).into_owned())
                };
                match tag.as_str() {
                    "Piece" => {
                        file.n_points = attr("NumberOfPoints")
                            .and_then(|n| n.parse().ok())
                            .ok_or("a Piece without NumberOfPoints")?;
                    }
                    "DataArray" => {
                        if attr("format").as_deref() != Some("binary") {
                            return Err("only inline binary arrays are read".into());
                        }
                        open = Some(VtpArray {
                            section: section.clone(),
                            name: attr("Name").unwrap_or_default(),
                            vtk_type: attr("type").unwrap_or_default(),
                            components: attr("NumberOfComponents")
                                .and_then(|n| n.parse().ok())
                                .unwrap_or(1),
                            values: Vec::new(),
                        });
                    }
                    _ => section = tag,
                }
            }
            Event::Text(t) => {
                if let Some(a) = open.as_mut() {
                    let text: Cow<str> = t.decode().map_err(|e| e.to_string())?;
                    a.values = decode_values(&a.vtk_type, &text)
                        .ok_or_else(|| format!("array '{}' is not valid binary data", a.name))?;
                }
            }
            Event::End(e) if e.name().as_ref() == b"DataArray" => {
                file.arrays.extend(open.take());
            }
            Event::Eof => break,
            _ => {}
        }
    }
    Ok(file)
}

/// The values of a binary array of `vtk_type`: base64 of a `UInt64` byte
/// count and that many bytes.
fn decode_values(vtk_type: &str, text: &str) -> Option<Vec<f64>> {
    let bytes = base64_decode(text)?;
    let (head, body) = bytes.split_at_checked(8)?;
    let count = u64::from_le_bytes(head.try_into().ok()?) as usize;
    if count != body.len() {
        return None;
    }
    let values = match vtk_type {
        "Float64" => body
            .chunks_exact(8)
            .map(|c| c.try_into().map(f64::from_le_bytes))
            .collect::<Result<Vec<_>, _>>()
            .ok()?,
        "UInt64" => body
            .chunks_exact(8)
            .map(|c| c.try_into().map(|b| u64::from_le_bytes(b) as f64))
            .collect::<Result<Vec<_>, _>>()
            .ok()?,
        "UInt32" => body
            .chunks_exact(4)
            .map(|c| c.try_into().map(|b| f64::from(u32::from_le_bytes(b))))
            .collect::<Result<Vec<_>, _>>()
            .ok()?,
        _ => return None,
    };
    Some(values)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trips_every_length() {
        assert_eq!(base64_encode(b""), "");
        assert_eq!(base64_encode(b"f"), "Zg==");
        assert_eq!(base64_encode(b"fo"), "Zm8=");
        assert_eq!(base64_encode(b"foo"), "Zm9v");
        assert_eq!(base64_encode(b"foob"), "Zm9vYg==");
        let bytes: Vec<u8> = (0..=255).collect();
        for n in 0..bytes.len() {
            let text = base64_encode(&bytes[..n]);
            assert_eq!(base64_decode(&text).as_deref(), Some(&bytes[..n]), "{n}");
        }
        assert_eq!(base64_decode("Zm9v!"), None);
        assert_eq!(base64_decode("Zg=a"), None);
        assert_eq!(base64_decode("Zg==Zm9v"), None);
    }

    #[test]
    fn a_piece_is_written_in_the_vtk_layout_and_read_back() {
        let points = [0.0, 1.0, 2.0, -1.5, 1e-300, f64::MAX];
        let velocity = [0.25, -0.5, 3.0, 1.0, 2.0, 0.1];
        let speed = [1.0, 2.5];
        let counts = [3u32, 0];
        let (connectivity, offsets) = ([0u64, 1], [1u64, 2]);
        let piece = Piece {
            points: &points,
            point_data: vec![
                DataArray::named("velocity", 3, Values::F64(&velocity)),
                DataArray::named("speed", 1, Values::F64(&speed)),
                DataArray::named("contact_count", 1, Values::U32(&counts)),
            ],
            cells: Cells::Verts,
            connectivity: &connectivity,
            offsets: &offsets,
        };
        let text = String::from_utf8(piece.to_xml()).expect("utf-8");
        assert!(
            text.starts_with(
                "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" \
                 header_type=\"UInt64\"><PolyData><Piece NumberOfPoints=\"2\" NumberOfLines=\"0\" \
                 NumberOfStrips=\"0\" NumberOfPolys=\"0\" NumberOfVerts=\"2\"><PointData \
                 Scalars=\"speed\" Vectors=\"velocity\"><DataArray type=\"Float64\" \
                 Name=\"velocity\" format=\"binary\" NumberOfComponents=\"3\">"
            ),
            "{text}"
        );
        assert!(
            text.ends_with("</Verts></Piece></PolyData></VTKFile>"),
            "{text}"
        );
        let file = parse_vtp(&text).expect("reads back");
        assert_eq!(file.n_points, 2);
        let names: Vec<(&str, &str)> = file
            .arrays
            .iter()
            .map(|a| (a.section.as_str(), a.name.as_str()))
            .collect();
        assert_eq!(
            names,
            [
                ("PointData", "velocity"),
                ("PointData", "speed"),
                ("PointData", "contact_count"),
                ("Points", ""),
                ("Verts", "connectivity"),
                ("Verts", "offsets"),
            ]
        );
        // Bit for bit, extremes included.
        assert_eq!(file.arrays[3].values, points);
        assert_eq!(file.point_data("velocity").expect("v").values, velocity);
        let counts = file.point_data("contact_count").expect("counts");
        assert_eq!(
            (counts.vtk_type.as_str(), counts.values.clone()),
            ("UInt32", vec![3.0, 0.0])
        );
        // A byte count that does not match its data is refused.
        let broken = text.replacen("<DataArray type=\"Float64\" Name=\"speed\" format=\"binary\" NumberOfComponents=\"1\">", "<DataArray type=\"UInt32\" Name=\"speed\" format=\"binary\" NumberOfComponents=\"1\">", 1);
        assert!(
            parse_vtp(&broken)
                .is_ok_and(|f| f.point_data("speed").is_some_and(|a| a.values.len() == 4))
        );
        let truncated = text.replacen("AAAAAAAA", "AAAA", 1);
        assert!(parse_vtp(&truncated).is_err());
    }

    #[test]
    fn the_enclosure_is_a_ring_of_quads_and_two_caps() {
        let dump = VtkDump::new(Path::new("."), 0.01, 0.0, 0.01, 0.03);
        let (points, connectivity, offsets) = dump.enclosure(0.002);
        assert_eq!(points.len(), 3 * 2 * SEGMENTS);
        assert_eq!(offsets.len(), SEGMENTS + 2);
        assert_eq!(connectivity.len(), 4 * SEGMENTS + 2 * SEGMENTS);
        assert_eq!(offsets.last().copied(), Some(connectivity.len() as u64));
        // First point at angle 0 on the lower rim, shifted by the displacement.
        assert_eq!(&points[..3], &[0.01, 0.0, 0.002]);
        assert_eq!(points[3 * SEGMENTS + 2], 0.032);
    }
}
