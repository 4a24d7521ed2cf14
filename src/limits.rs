//! The limits every input is checked against before any work, each with its reason. Inside
//! them the solvers are accurate and every loop ends; outside, an input is refused with a
//! message that names it (or, for accuracy, warned about), never run into a wrong answer, an
//! endless loop or an allocation failure. `docs/faults.md` lists them with their tests.

/// Samples of one record (2²⁴ ≈ 16.8 million: 46 h at 0.01 s). Records are held in memory and
/// every simulation crosses every sample.
pub const MAX_SAMPLES: usize = 1 << 24;

/// Bytes of one input file read whole (a record, a config, a target table): 1 GiB.
pub const MAX_FILE_BYTES: u64 = 1 << 30;

/// Why an input file was not read.
#[derive(Debug)]
pub enum InputFileError {
    Io(std::io::Error),
    /// Its size, bytes, above [`MAX_FILE_BYTES`].
    TooLarge(u64),
}

/// The bytes of an input file (a record, a config, a target table), refused above
/// [`MAX_FILE_BYTES`] before they are read.
pub fn read_input_file(path: &std::path::Path) -> Result<Vec<u8>, InputFileError> {
    let bytes = std::fs::metadata(path).map_err(InputFileError::Io)?.len();
    if bytes > MAX_FILE_BYTES {
        return Err(InputFileError::TooLarge(bytes));
    }
    std::fs::read(path).map_err(InputFileError::Io)
}

/// The text of an input file's bytes, a leading byte-order mark dropped; not UTF-8, the error
/// reading them as text would give.
pub fn input_text(bytes: &[u8]) -> Result<&str, std::io::Error> {
    let text = std::str::from_utf8(bytes).map_err(|_| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "stream did not contain valid UTF-8",
        )
    })?;
    Ok(text.strip_prefix('\u{feff}').unwrap_or(text))
}

/// Sample interval of a record, s: 10 µs … 1 s. Accelerograms are sampled at 0.001–0.05 s; a
/// step outside this range is a unit or header mistake, and a step of 1e-15 s would make every
/// record-length loop astronomically long.
pub const DT_RANGE_S: (f64, f64) = (1e-5, 1.0);

/// Largest peak ground acceleration a simulation takes, g, after scaling (a record times
/// `simulate --scale`, an IDA run's record times its intensity factor): a million g. No
/// earthquake exceeds a few g, an IDA stops at collapse (tens of g; the repository's caps are
/// 5 g at most) and `--scale` ≤ 1e6 on a record of up to 1 g stays inside; a larger peak is a
/// unit or scale mistake, and its results would be round-off. The exact integrators decide
/// stick and slip within `1e-10` of each interface's friction force, while the floors'
/// accelerations carry round-off relative to the record's: once the record is some 10⁸ times
/// the friction acceleration `μ·g`, a block can break loose and stick again at one instant
/// without end (refused as Zeno behaviour; measured under the fixture records: stacks of `μ`
/// 0.1–0.2 on a three-storey building from 1.5e7 g, one storey up to 2e11 g; a record that
/// alternates ±9e5 g every sample already at 9e5 g), and from about 1e150 g the squares of
/// velocities overflow. Subnormal records (1e-310 g) are within it and run (at rest).
pub const MAX_PEAK_ACCEL_G: f64 = 1e6;

/// Oscillator periods of a spectrum or of a matching grid, s: 1 ms … 10⁴ s.
pub const PERIOD_RANGE_S: (f64, f64) = (1e-3, 1e4);

/// Period of the bare structure in a simulation, s: 1 µs (rigid to double precision against any
/// record step; the tests use it as a rigid base) … 10⁴ s.
pub const STRUCTURE_PERIOD_RANGE_S: (f64, f64) = (1e-6, 1e4);

/// Periods in one list (a spectrum's, the matcher's check grid, the study grid's `T_p`).
pub const MAX_PERIODS: usize = 100_000;

/// Motions per zone (stochastic seeds or record files).
pub const MAX_MOTIONS: usize = 10_000;

/// Blocks in a stack. Stored sweep variables have one dimension per block mass ratio and per
/// friction coefficient, plus motion, `T_p` and interface, and HDF5 allows 32 dimensions:
/// `3 + 2n ≤ 32`.
pub const MAX_BLOCKS: usize = 14;

/// Values in one grid axis (a list or an expanded `{from, to, step}` range).
pub const MAX_AXIS_VALUES: usize = 100_000;

/// Case results of a study (cases × motions, all zones together). `sweep.h5` is assembled in
/// memory at about 60 bytes per case result: 50 million is about 3 GB.
pub const MAX_CASE_RESULTS: u64 = 50_000_000;

/// Largest mass ratio of one block, and of the whole stack. Beyond `10⁴` the structure is a
/// negligible appendage of its load and the energy balance of the exact integrator loses more
/// than `1e-6` of the input to round-off (measured: `2e-6` at `α = 10⁴`, `4e-2` at `10⁶`).
pub const MAX_ALPHA: f64 = 1e4;

/// Largest friction coefficient: no surface pair has more than a few; above this a stack simply
/// never slides, which any `μ` of a few tens already gives.
pub const MAX_MU: f64 = 1e3;

/// Yield strength ratio `C_y = F_y/(m_p·g)` of a yielding structure. Below `1e-6` the
/// structure is a mass on a damper whose yield displacement (`C_y·g/ω_p²`, under a micrometre at
/// `T_p = 1 s`) makes the ductility a ratio of round-off; above `1e6` (a million g) nothing a
/// record can do reaches the yield force, and the value is a unit mistake rather than a design.
pub const STRENGTH_RATIO_RANGE: (f64, f64) = (1e-6, 1e6);

/// Largest damping ratio of the post-yield branch, `ζ_p/√r` with `ζ_p` the bare structure's
/// ratio and `r > 0` the post-yield stiffness ratio (at its largest when every block slides).
/// The exact integrator writes a branch's free motion as `e^{−aτ}(c·cos ωτ + d·sin ωτ)`: an
/// overdamped branch has no such form (it would need hyperbolic functions; refused), and near
/// critical damping `ω → 0` makes `d ∝ 1/ω`, so the bounds of the certified search loosen by
/// that factor. `0.9` keeps the loss below a factor `1/sqrt(1 − 0.9²) ≈ 2.3`.
/// `r = 0` (elastic–perfectly plastic) has its own exact form and is always allowed.
pub const MAX_POST_YIELD_DAMPING: f64 = 0.9;

/// Largest target ductility of a constant-ductility spectrum. The strength search scans down
/// from the elastic strength in steps of [`DUCTILITY_SCAN_STEP`], about `ln(μ)/0.02` runs; 100
/// is far beyond any structure's capacity (Chopra's spectra stop at 8).
pub const MAX_TARGET_DUCTILITY: f64 = 100.0;

/// Ratio of successive strengths `f̄_y = C_y/C_e` in the downward scan of a constant-ductility
/// spectrum (`src/spectrum/ductility.rs`): the largest strength with the target ductility is
/// found to within this step before bisection refines it; a root inside an excursion of
/// `μ(f̄_y)` narrower than 2 % of `f̄_y` can be missed.
pub const DUCTILITY_SCAN_STEP: f64 = 0.98;

/// Runs of one incremental dynamic analysis trace (hunt, bracket and fill together; the hunt's
/// count follows from `cap_sa_g`, `first_sa_g` and the step increment). Every run is a full
/// simulation of the record; a few tens trace a curve (Vamvatsikos & Cornell 2002 use 12), and
/// ten times that bounds a config's mistake (a first step of 1e-9 g) instead of running for days.
pub const MAX_IDA_TRACE_RUNS: usize = 200;

/// Cases of a `floor_spectra:` section: each runs on every frame under every motion of every
/// zone, twice (sliding, attached), on its record refined 64 times.
pub const MAX_FLOOR_SPECTRA_CASES: usize = 100;

/// Cases of an IDA section: each is traced under every motion of every zone, twice (the stack
/// and the rigidly attached load).
pub const MAX_IDA_CASES: usize = 1_000;

/// Intensities of the common IDA grid (curves, fractiles, fragility stripes): stored arrays
/// are `records × cases × intensities × demands`, and a grid finer than the traced runs adds
/// only interpolated points.
pub const MAX_IDA_GRID_POINTS: usize = 1_000;

/// Zeros appended to every record so the residual drift is read near rest, s: each second is
/// simulated in every run; ten minutes is far beyond any free-vibration decay of a damped
/// structure.
pub const MAX_IDA_PAD_S: f64 = 600.0;

/// RK4 sub-steps per record interval (the accuracy bench goes to 1000).
pub const MAX_RK4_SUBSTEPS: usize = 100_000;

/// `ω_max·h` of an RK4 step: the method is stable on the imaginary axis up to `2√2 ≈ 2.83`; a
/// margin keeps the damped structure safely inside.
pub const RK4_MAX_OMEGA_STEP: f64 = 2.5;

/// Storeys of a building. Each contact and yield state of a building needs the eigenvectors of
/// its `2N × 2N` state matrix (`O(N³)`, cached per state) and every piece evaluates `O(N²)`
/// modal terms: at 60 storeys a run of a real record takes seconds to minutes; shear buildings
/// of more storeys are beyond what a shear model describes anyway.
pub const MAX_STOREYS: usize = 60;

/// Stacks in one building (any number may share a floor; each is a chain of up to
/// [`MAX_BLOCKS`]): the contact state is chosen floor by floor over all of a floor's stacks.
pub const MAX_STACKS: usize = 64;

/// A building's relative floor masses and storey stiffnesses: within `1e-6 … 1e6` of each other
/// (a ratio of `1e12` between two storeys makes the modes of the stiff one round-off).
pub const STOREY_RATIO_RANGE: (f64, f64) = (1e-6, 1e6);

/// Nesting depth of a YAML config (the study's is 4).
pub const MAX_YAML_DEPTH: usize = 32;

/// Characters of user input echoed back in a message.
pub const ECHO_CHARS: usize = 40;

/// `text` shortened for a message: at most [`ECHO_CHARS`] characters, with `…` and the total
/// length when cut.
pub fn excerpt(text: &str) -> String {
    let mut chars = text.chars();
    let head: String = chars.by_ref().take(ECHO_CHARS).collect();
    if chars.next().is_none() {
        head
    } else {
        format!("{head}… ({} bytes)", text.len())
    }
}

/// A parser's message cut to a readable length (its location, at the end, kept): a message may
/// quote an input value whole.
pub fn excerpt_message(message: &str) -> String {
    const HEAD: usize = 160;
    const TAIL: usize = 80;
    let chars: Vec<char> = message.chars().collect();
    if chars.len() <= HEAD + TAIL + 20 {
        return message.to_string();
    }
    let head: String = chars[..HEAD].iter().collect();
    let tail: String = chars[chars.len() - TAIL..].iter().collect();
    format!("{head} … {tail}")
}

/// Nesting depth of YAML text by its flow brackets and block indentation, without parsing it:
/// checked before a parser that is quadratic in the depth sees it.
pub fn yaml_depth(text: &str) -> usize {
    let mut deepest = 0;
    let mut indents: Vec<usize> = Vec::new();
    for line in text.lines() {
        let body = line.trim_start();
        if body.is_empty() || body.starts_with('#') {
            continue;
        }
        let indent = line.len() - body.len();
        while indents.last().is_some_and(|&i| i >= indent) {
            indents.pop();
        }
        indents.push(indent);
        let mut flow: usize = 0;
        let mut flow_max = 0;
        let mut quote: Option<char> = None;
        for c in body.chars() {
            match (quote, c) {
                (Some(q), c) if c == q => quote = None,
                (Some(_), _) => {}
                (None, '"' | '\'') => quote = Some(c),
                (None, '#') => break,
                (None, '[' | '{') => {
                    flow += 1;
                    flow_max = flow_max.max(flow);
                }
                (None, ']' | '}') => flow = flow.saturating_sub(1),
                _ => {}
            }
        }
        deepest = deepest.max(indents.len() + flow_max);
    }
    deepest
}

/// A name that becomes part of an HDF5 path or a coordinate (a zone, a limit state): letters,
/// digits, `_` or `-`, and not one of `earlier`'s; `Err(why)`.
pub fn check_name<'a>(
    name: &str,
    mut earlier: impl Iterator<Item = &'a str>,
) -> Result<(), String> {
    let word = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '-';
    if name.is_empty() || !name.chars().all(word) {
        return Err(format!("`{name}` must be letters, digits, `_` or `-`"));
    }
    if earlier.any(|o| o == name) {
        return Err(format!("`{name}` appears twice"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn excerpt_cuts_long_text_only() {
        assert_eq!(excerpt("0.x3"), "0.x3");
        let long = "9".repeat(1000);
        let e = excerpt(&long);
        assert!(e.starts_with(&"9".repeat(ECHO_CHARS)) && e.ends_with("… (1000 bytes)"));
        assert!(e.chars().count() < 60);
    }

    #[test]
    fn yaml_depth_counts_blocks_and_brackets() {
        assert_eq!(yaml_depth("a: 1\nb: 2\n"), 1);
        assert_eq!(yaml_depth("a:\n  b:\n    c: [1, {d: 2}]\n"), 5);
        assert_eq!(yaml_depth("x: \"[[[[\" # [[[\n"), 1);
        assert_eq!(yaml_depth(&format!("x: {}", "[".repeat(100))), 101);
        let study =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/paper.yaml"))
                .unwrap();
        assert!(yaml_depth(&study) <= 5);
    }
}
