//! The names by which a record's columns are known: the time column's names
//! and LAMMPS' reference prefixes. No thesis equation lives here; the CSV and
//! LAMMPS readers, their errors and `vlab replay` share these, so the file
//! imports nothing.

/// Names of a time column, compared case-insensitively after LAMMPS'
/// `v_` / `c_` / `f_` prefix is stripped ([`strip_lammps_prefix`]); a CSV
/// header cell may add the unit, which must then be seconds (`time [s]`).
pub const TIME_NAMES: [&str; 4] = ["t", "time", "time_s", "t_s"];

/// [`TIME_NAMES`] as messages list them.
pub const TIME_NAMES_TEXT: &str = "t, time, time_s or t_s (any case, with or without LAMMPS' v_ \
     prefix; a CSV header may add the unit: 'time [s]')";

/// `v_time` -> `time`, `c_force[3]` -> `force[3]`, `f_avg` -> `avg`; other
/// names unchanged. LAMMPS' prefixes say what kind of quantity a column
/// holds, not what it is, so names are compared without them.
pub fn strip_lammps_prefix(name: &str) -> &str {
    for prefix in ["v_", "c_", "f_"] {
        if let Some(rest) = name.strip_prefix(prefix)
            && !rest.is_empty()
        {
            return rest;
        }
    }
    name
}

/// True when `name` (without a unit) is one of [`TIME_NAMES`].
pub fn is_time_name(name: &str) -> bool {
    let bare = strip_lammps_prefix(name).to_ascii_lowercase();
    TIME_NAMES.contains(&bare.as_str())
}

/// The time column among the column `names` (as written, without units):
/// the one named `given` exactly, else the first of a time name; `None` when
/// there is none.
pub fn time_column_index(names: &[&str], given: Option<&str>) -> Option<usize> {
    match given {
        Some(given) => names.iter().position(|n| *n == given),
        None => names.iter().position(|n| is_time_name(n)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prefixes_are_lammps_reference_kinds() {
        assert_eq!(strip_lammps_prefix("v_time"), "time");
        assert_eq!(strip_lammps_prefix("c_f[3]"), "f[3]");
        assert_eq!(strip_lammps_prefix("v_"), "v_");
        assert_eq!(strip_lammps_prefix("velocity"), "velocity");
    }

    #[test]
    fn time_names_in_any_case_and_the_name_given() {
        for name in ["t", "time", "Time", "TIME", "time_s", "T_s", "v_time"] {
            assert!(is_time_name(name), "{name}");
        }
        for name in ["timestep", "TimeStep", "times", "seconds", "v_"] {
            assert!(!is_time_name(name), "{name}");
        }
        let names = ["step", "Time", "t"];
        assert_eq!(time_column_index(&names, None), Some(1));
        assert_eq!(time_column_index(&names, Some("step")), Some(0));
        assert_eq!(time_column_index(&names, Some("time")), None);
        assert_eq!(time_column_index(&["step", "v"], None), None);
    }
}
