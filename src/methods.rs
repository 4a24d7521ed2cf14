//! The version of every method whose numbers the study stores. A stage's fingerprint names the
//! versions of the methods it computes with ([`Method`], listed per stage by
//! `pipeline::StageId::methods`), so a binary whose numerics changed finds the files of an
//! earlier one out of date instead of reading them as current, and `status` names the versions
//! a stale file was made with.
//!
//! **Bump a version whenever a change can alter a stored number** (not only its meaning: any
//! bit). `tests/methods.rs` holds golden hashes of every stage's stored variables on
//! `configs/quick.yaml`, `configs/mdof-quick.yaml` and `configs/ida-quick.yaml` beside these
//! versions, and fails, naming the method to bump, when the numbers change and the versions do
//! not.

/// One method and its version.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Method {
    pub name: &'static str,
    pub version: u32,
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}-{}", self.name, self.version)
    }
}

/// The exact event-driven integrators (one storey and building), the systems a case is run as
/// and the sweep's skip rules (`dynamics`, `study::physics`, `study::sweep`) (3: a building
/// study's sweep stores the floors' absolute velocities and the residual drifts; 4: every
/// sweep stores the goods' own demands, each block's peak absolute acceleration and velocity
/// and each interface's residual slip; 5: a peak's extremum is refined by Newton's method on
/// its slope to a certified `ε/8` of its value, not its time to a few ulps of `dt`: every
/// stored peak moves at round-off, its time by up to about `√ε` of the motion's time scale;
/// 6: the sweep's rule `held_at_lower_friction`, `skip_rule` 3, where a stack repeats an
/// earlier case's run: no stored number moves, the codes do; 7: within a mode a building's
/// piece starts from the last piece's modal state, not from the floors' state projected again,
/// and its constant loads are projected once per mode: a building's stored peaks move at
/// round-off; 8: a building's peaks are searched only on the pieces that can still hold them,
/// each from the peak known when it is searched (`dynamics::deferred`): a stored peak can move
/// at round-off, none did on the golden configs or on a sweep shard of `configs/mdof.yaml`).
pub const INTEGRATOR: Method = Method {
    name: "integrator",
    version: 8,
};

/// Exact response spectra (`spectrum::response`), with the target spectra they are compared to.
pub const SPECTRUM: Method = Method {
    name: "spectrum",
    version: 1,
};

/// The motions: stochastic seeds, record processing and spectral matching with the set checks
/// (`ground_motion`, `study::motions`).
pub const MOTIONS: Method = Method {
    name: "motions",
    version: 1,
};

/// `T_new`, the displacement response ratios and the bands (`study::tnew`, the tnew stage).
pub const TNEW: Method = Method {
    name: "tnew",
    version: 2,
};

/// A building study's attached fractions: `λ` and its kin (`study::attached`).
pub const LAMBDA: Method = Method {
    name: "lambda",
    version: 2,
};

/// The design equations' fits, folds, metrics and recommendation (`fit`, the fit stage).
pub const FIT: Method = Method {
    name: "fit",
    version: 1,
};

/// Incremental dynamic analysis: tracing, curves and fragilities (`ida`, `study::ida`).
pub const IDA: Method = Method {
    name: "ida",
    version: 1,
};

/// A study's floor response spectra: the refinement of the record and the spectra of the
/// floors' histories (`spectrum::floor`, `study::floors`, the floors stage).
pub const FLOORS: Method = Method {
    name: "floors",
    version: 1,
};

/// The report's pages and figures (7: the design page's data by name, `ZoneDesign`'s
/// `building` and `lambda`; 8: where the stacks would rock, the table and the design page's
/// note; 9: the design page's `rocks_share` row; 10: ASCE 7-22's floor spectrum in the floors
/// figure; 11: the design page takes the stack at mid-height, `mid`; 12: the design page's
/// opening paragraph names `mid` among the floors an address may give).
pub const REPORT: Method = Method {
    name: "report",
    version: 12,
};

/// The methods as they enter a fingerprint: `name-version` joined by spaces.
pub fn tag(methods: &[Method]) -> String {
    methods
        .iter()
        .map(Method::to_string)
        .collect::<Vec<_>>()
        .join(" ")
}

/// A stage's fingerprint: the hash of its inputs followed by its methods' tag in brackets, so
/// that the methods a file was made with can be read back ([`methods_of`]).
pub fn fingerprint(inputs_hash: &str, methods: &[Method]) -> String {
    format!("{inputs_hash} [{}]", tag(methods))
}

/// The methods' tag of a fingerprint made by [`fingerprint`] (`None` for an older one).
pub fn methods_of(fingerprint: &str) -> Option<&str> {
    let (_, rest) = fingerprint.split_once(" [")?;
    rest.strip_suffix(']')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fingerprint_gives_back_its_methods() {
        // Methods of their own, not the constants: the format is checked, not today's versions.
        let method = |name, version| Method { name, version };
        let fp = fingerprint("abc", &[method("integrator", 2), method("spectrum", 1)]);
        assert_eq!(fp, "abc [integrator-2 spectrum-1]");
        assert_eq!(methods_of(&fp), Some("integrator-2 spectrum-1"));
        assert_eq!(methods_of("abc"), None);
    }
}
