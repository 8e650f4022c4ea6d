//! A sweep's results as the host model's dissipation map
//! ([`crate::host::DissipationMap`]): the mean efficiency over seeds at each
//! frequency and Γ with its error ([`super::sweep::summarise`]), the
//! particles' mass from `E_max = 4 (Γ g / ω)² M` (thesis eq. 6.10) and the
//! sweep's own gravity, for one fill ratio and orientation.

use std::f64::consts::TAU;

use crate::host::{DissipationMap, MapPoint};
use crate::scene::Orientation;
use crate::validation::InvalidParameter;

use super::sweep::{RowStatus, SweepFile, summarise};

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
