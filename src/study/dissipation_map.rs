//! A sweep's results as the host model's dissipation map
//! ([`crate::host::DissipationMap`]): the mean efficiency over seeds at each
//! frequency and Γ with its error ([`super::sweep::summarise`]), the
//! particles' mass from `E_max = 4 (Γ g / ω)² M` (thesis eq. 6.10) and the
//! sweep's own gravity, for one fill ratio and orientation.

use std::f64::consts::TAU;
use std::path::PathBuf;

use crate::host::{DissipationMap, MapPoint};
use crate::scene::Orientation;
use crate::validation::InvalidParameter;

use super::sweep::{RowStatus, SweepError, SweepFile, SweepRow, summarise};

/// Which efficiency of a sweep a map holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapSource {
    /// The DEM's own (its ledger).
    Dem,
    /// The rig's, by Yang's structure-independent method (thesis Ch. 7).
    Yang,
}

/// The map of `file` at `orientation` and `fill_ratio` (each may be left
/// out when the sweep has only one), of the DEM's efficiency or Yang's.
pub fn dissipation_map(
    file: &SweepFile,
    orientation: Option<Orientation>,
    fill_ratio: Option<f64>,
    source: MapSource,
) -> Result<DissipationMap, InvalidParameter> {
    let grid = &file.header.grid;
    let orientation = match (orientation, grid.orientations.as_slice()) {
        (Some(o), _) => o,
        (None, [only]) => *only,
        (None, many) => {
            return Err(InvalidParameter::new(
                "orientation",
                "not given",
                "",
                format!(
                    "one of the sweep's: {}",
                    many.iter()
                        .map(|o| o.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
    };
    let fill = match (fill_ratio, grid.fill_ratios.as_slice()) {
        (Some(f), _) => f,
        (None, [only]) => *only,
        (None, many) => {
            return Err(InvalidParameter::new(
                "fill_ratio",
                "not given",
                "",
                format!(
                    "one of the sweep's: {}",
                    many.iter()
                        .map(f64::to_string)
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
    };
    let g = file.header.gravity_mps2;
    // The particles' mass from any ok row's E_max (eq. 6.10): every row of
    // one scene has the same.
    let mass = file.rows.iter().find_map(|r| {
        let c = &r.condition;
        (r.status == RowStatus::Ok && c.orientation == orientation && c.fill_ratio == fill).then(
            || {
                let v = c.gamma * g / (TAU * c.freq_hz);
                r.e_max_j / (4.0 * v * v)
            },
        )
    });
    let Some(mass) = mass else {
        return Err(InvalidParameter::new(
            "map",
            format!("no ok row at {} and fill {fill}", orientation.as_str()),
            "",
            "at least one ok condition",
        ));
    };
    let points: Vec<MapPoint> = summarise(file)
        .iter()
        .filter(|s| s.orientation == orientation && s.fill_ratio == fill && s.n > 0)
        .map(|s| MapPoint {
            freq_hz: s.freq_hz,
            gamma: s.gamma,
            efficiency: match source {
                MapSource::Dem => s.efficiency,
                MapSource::Yang => s.efficiency_measured,
            },
            efficiency_se: s.efficiency_se,
            apparent_mass_kg: s.apparent_mass_kg.is_finite().then_some(s.apparent_mass_kg),
        })
        .collect();
    DissipationMap::new(&points, mass, g)
}

/// The sweep files at `paths` as one map's rows: the first file's, with
/// every condition (fill ratio, orientation, frequency, Γ) that a later
/// file holds taken from that file instead (all its seeds, and only its:
/// a refinement that reruns a condition with more seeds does not count the
/// first seed twice), and the lists of conditions joined. So a coarse map
/// is refined where it is too coarse, at a bouncing bed's onset, by a sweep
/// over a finer Γ grid and several seeds there, without sweeping the whole
/// map again. Every file must have been swept with the first's protocol
/// (scene, rig, shaker and vlab version: [`super::sweep::SweepHeader`]'s
/// `protocol_id`), or its efficiencies would not be comparable. The
/// header's `carried` names the branches of carried sweeps among the files.
pub fn read_map_files(paths: &[PathBuf]) -> Result<SweepFile, SweepError> {
    let Some((first_path, rest)) = paths.split_first() else {
        return Err(SweepError::Merge("no map file given".into()));
    };
    let mut map = SweepFile::read(first_path)?;
    let mut branches: Vec<String> = map.header.carried.iter().cloned().collect();
    for path in rest {
        let finer = SweepFile::read(path)?;
        if let Some(b) = &finer.header.carried
            && !branches.contains(b)
        {
            branches.push(b.clone());
        }
        if finer.header.protocol_id != map.header.protocol_id {
            return Err(SweepError::Merge(format!(
                "{} was swept with another protocol than {} (protocol_id {} against {}: the scene, \
                 rig, shaker or vlab version differ), so their efficiencies are not comparable",
                path.display(),
                first_path.display(),
                finer.header.protocol_id,
                map.header.protocol_id
            )));
        }
        let place = |r: &SweepRow| {
            let c = &r.condition;
            (
                c.fill_ratio.to_bits(),
                c.orientation,
                c.freq_hz.to_bits(),
                c.gamma.to_bits(),
            )
        };
        let replaced: Vec<_> = finer.rows.iter().map(place).collect();
        map.rows.retain(|r| !replaced.contains(&place(r)));
        map.rows.extend(finer.rows.iter().cloned());
        let (to, from) = (&mut map.header.grid, &finer.header.grid);
        let by_bits = |a: &f64, b: &f64| a.to_bits() == b.to_bits();
        join(&mut to.freqs_hz, &from.freqs_hz, by_bits);
        join(&mut to.gammas, &from.gammas, by_bits);
        join(&mut to.fill_ratios, &from.fill_ratios, by_bits);
        join(&mut to.seeds, &from.seeds, u64::eq);
        join(&mut to.orientations, &from.orientations, Orientation::eq);
        for list in [&mut to.freqs_hz, &mut to.gammas, &mut to.fill_ratios] {
            list.sort_by(f64::total_cmp);
        }
        to.seeds.sort_unstable();
    }
    // A carried sweep's branch among the files: the map is that branch's
    // where it holds conditions ([`super::sweep_updown`]).
    map.header.carried = (!branches.is_empty()).then(|| branches.join(", "));
    map.sort_canonical();
    Ok(map)
}

/// The label of a map read from `paths` ([`read_map_files`]): the files
/// joined by ` + `.
pub fn map_files_label(paths: &[PathBuf]) -> String {
    paths
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(" + ")
}

/// `to` with the values of `from` it lacks (by `same`), in `from`'s order
/// after its own.
fn join<T: Copy>(to: &mut Vec<T>, from: &[T], same: impl Fn(&T, &T) -> bool) {
    for v in from {
        if !to.iter().any(|t| same(t, v)) {
            to.push(*v);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kept(name: &str) -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("signals/reference")
            .join(name)
    }

    #[test]
    fn a_finer_sweep_replaces_the_conditions_it_holds() {
        // The plate's map (one seed, Γ 14 and 17 at 40 Hz, the bed's onset
        // between) refined by a sweep of Γ 14-17 at 40 Hz over seeds 1-3:
        // at Γ 14 and 17 the three seeds replace the map's one (seed 1,
        // which both files hold, counted once); Γ 15 and 16 join; the other
        // frequencies keep their rows.
        let coarse = kept("host-map/sweep.csv");
        let finer = kept("host-map-onset/sweep-40hz.csv");
        let base = SweepFile::read(&coarse).expect("reads");
        let map = read_map_files(&[coarse.clone(), finer.clone()]).expect("refines");
        let rows_at = |file: &SweepFile, f: f64, g: f64| {
            file.rows
                .iter()
                .filter(|r| r.condition.freq_hz == f && r.condition.gamma == g)
                .count()
        };
        for g in [14.0, 15.0, 16.0, 17.0] {
            assert_eq!(rows_at(&map, 40.0, g), 3, "40 Hz, Γ {g}");
        }
        assert_eq!(rows_at(&base, 40.0, 14.0), 1);
        for f in [34.0, 37.0, 43.0, 46.0] {
            for g in [1.5, 14.0, 30.0] {
                assert_eq!(rows_at(&map, f, g), rows_at(&base, f, g), "{f} Hz, Γ {g}");
            }
        }
        assert_eq!(map.rows.len(), base.rows.len() - 2 + 12);
        // The map's point is the three seeds' mean.
        let finer_file = SweepFile::read(&finer).expect("reads");
        let mean = finer_file
            .rows
            .iter()
            .filter(|r| r.condition.gamma == 16.0)
            .map(|r| r.efficiency)
            .sum::<f64>()
            / 3.0;
        let m = dissipation_map(&map, None, None, MapSource::Dem).expect("a map");
        let column = &m.columns[m.freqs_hz.iter().position(|f| *f == 40.0).expect("40 Hz")];
        let point = column.iter().find(|p| p.gamma == 16.0).expect("Γ 16");
        assert!(
            (point.efficiency - mean).abs() < 1e-12,
            "{point:?} against {mean}"
        );
        assert_eq!(column.len(), 12);
        // A sweep of another protocol is refused, naming both files.
        let other = kept("sweep-steady/sweep.csv");
        let err = read_map_files(&[coarse, other]).expect_err("another protocol");
        let text = err.to_string();
        assert!(
            text.contains("another protocol") && text.contains("sweep-steady"),
            "{text}"
        );
    }
}
