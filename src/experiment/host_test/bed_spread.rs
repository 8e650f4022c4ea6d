//! The bed-to-bed part of a host test's error: how far independent beds of
//! one damper spread beyond what one record can see, and how it is known.
//!
//! A run's own error ([`crate::stats::mean_stderr`]) is that of its
//! window's cycles or its record's periods. Independent beds of the same
//! damper (poured with other seeds) can differ by more: at 40 Hz, Γ 20 the
//! means of beds spread by about 1 % while each window claims 0.5 %
//! (`docs/accuracy.md`, "Coverage of the printed error"). A shake measures
//! that part every run, from an ensemble of beds
//! ([`crate::experiment::ensemble`]); the table of three shake conditions
//! that used to add it is retired. The host's stepped sine does the same
//! with `--beds N` ([`BedToBed::Ensemble`]); one bed there adds the part
//! measured over 20 beds at four points of the built-in host
//! ([`crate::experiment::host_test::frf::bed_to_bed`]) and nothing elsewhere.

use serde::Serialize;

use crate::scene::Scene;

/// The bed-to-bed part of a run's error, and how it is known.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "source", rename_all = "snake_case")]
pub enum BedToBed {
    /// Measured over `beds` beds of this damper at this condition.
    Measured { rel: f64, beds: u32 },
    /// Not measured for this damper or condition: the +- is the record's.
    NotMeasured,
    /// Measured by the run itself: the figure is the mean over `beds`
    /// independent beds and its +- their spread's
    /// ([`crate::stats::ensemble_mean_floored`]).
    Ensemble { beds: u32 },
}

impl BedToBed {
    /// The part relative to the mean that is still to be added to a
    /// record's error: zero when not measured, and for an ensemble, whose
    /// error holds it already.
    pub fn rel(&self) -> f64 {
        match *self {
            BedToBed::Measured { rel, .. } => rel,
            BedToBed::NotMeasured | BedToBed::Ensemble { .. } => 0.0,
        }
    }
}

/// `scene` is the built-in thesis damper poured again: every setting but
/// the seed as [`Scene::thesis`]'s.
pub fn is_thesis_damper(scene: &Scene) -> bool {
    let thesis = Scene::thesis();
    let mut simulation = scene.simulation.clone();
    simulation.seed = thesis.simulation.seed;
    scene.particles == thesis.particles
        && scene.enclosure == thesis.enclosure
        && scene.contact == thesis.contact
        && simulation == thesis.simulation
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Any seed of the thesis damper is the thesis damper; another particle
    /// count is not. An ensemble's part is in its error already.
    #[test]
    fn the_thesis_damper_is_known_by_everything_but_its_seed() {
        let mut scene = Scene::thesis();
        scene.simulation.seed = 23;
        assert!(is_thesis_damper(&scene));
        scene.particles.count = 200;
        assert!(!is_thesis_damper(&scene));
        assert_eq!(BedToBed::Ensemble { beds: 6 }.rel(), 0.0);
        assert_eq!(
            BedToBed::Measured {
                rel: 0.07,
                beds: 20
            }
            .rel(),
            0.07
        );
    }
}
