//! The T_new stage: per zone and case, the mean peak displacements over the motions, `T_rigid`,
//! `T_new` read off the zone's mean 5 %-damped displacement spectrum (paper Section 7.1; the
//! rule for several crossings in [`crate::study::tnew`]), whether anything slid, `DRR_1` and
//! `DRR_2` → `tnew.h5` (layout in [`crate::store::tnew`]).
//!
//! The numbers are [`crate::study::tnew::ZoneWork`]'s (in a building study also the attached
//! fractions, [`crate::study::attached`]); the stage reads the motions and the sweep, calls it
//! per zone, reports and writes.
//!
//! **Work units.** In a building study nearly all of the stage's time goes to the attached
//! fractions, whose units ([`crate::study::attached::fraction_units`]: one per zone, distinct
//! building, `T_p` and total `α`) are computed each on its own and stored as it ends, in a unit
//! file under `tnew.units/` ([`crate::store::units`]: identity and checksum), so that an
//! interrupted stage resumes where it stopped and `--shard K/N` computes the units `i` with
//! `i mod N = K − 1` beside the other shards (the units numbered over the zones in order). The
//! unsharded stage computes what no unit file holds and writes `tnew.h5`, the same bytes
//! whatever the split and the threads; the unit files go once `tnew.h5` is written and verified.
//! A one-storey study has no units: its stage is the spectrum and the crossings, seconds.
//!
//! Fingerprint: the sweep's, the step of the spectrum's period grid, the methods' versions.

use super::{PipelineError, Session, StageId, StageOutcome, Study};
use crate::store::StoreError;
use crate::store::fingerprint::fingerprint as hash_parts;
use crate::store::tnew::{TnewMeta, write_tnew};
use crate::store::units::{Columns, Stored, UnitId, read_unit, write_unit};
use crate::study::attached::{CaseFractions, FRACTION_FLAGS, FractionFlag, FractionUnit, Means};
use crate::study::tnew::{
    self, BAND_FLAGS, SD_STEP_S, TNEW_FLAG_CODES, TnewError, ZoneInputs, fraction_units,
};
use rayon::prelude::*;
use std::path::PathBuf;

/// The directory of `tnew`'s unit files.
pub const UNITS_DIR: &str = "tnew.units";

/// The fingerprint `tnew.h5` must carry (`λ`'s definition and search are the `lambda` method's
/// version).
pub fn fingerprint(sweep_fingerprint: &str) -> String {
    let step = format!("sd_step_s={SD_STEP_S}");
    StageId::Tnew.fingerprint(&hash_parts(&[sweep_fingerprint, &step]))
}

/// Builds `tnew.h5`, or with `shard = Some((K, N))` only that shard's unit files: per zone,
/// reads the sweep, takes the units stored, computes the rest (each stored as it ends) and,
/// unsharded, finishes the zone ([`tnew::ZoneWork`]), reports and writes.
pub fn build(s: &Session, shard: Option<(usize, usize)>) -> Result<StageOutcome, PipelineError> {
    let study = &s.study;
    let me = StageId::Tnew;
    let grid = study.grid(me)?;
    let frames = study.frames();
    let store = FractionUnits::new(study)?;
    if shard.is_some() && store.total() == 0 {
        return Err(PipelineError::Setting {
            setting: "shard",
            why: "has nothing to split: tnew's work units are a building study's attached \
                  fractions, and a one-storey study has none (its tnew runs whole in seconds)"
                .into(),
        });
    }
    let in_shard = super::shard_filter(me, shard, store.total())?;
    let motions = super::files::motions(study)?;
    let physics = study.physics();
    let building = study.building();
    let keep_going = || !s.reporter.cancelled();
    let stopped = |e: TnewError| match e.is_stopped() {
        true => PipelineError::Cancelled(me),
        false => e.into(),
    };
    let mut zones = Vec::new();
    for (z, zc) in study.cfg.zones.iter().enumerate() {
        let mine: Vec<usize> = (0..store.units.len())
            .filter(|&u| in_shard(z * store.units.len() + u))
            .collect();
        if shard.is_some() && mine.is_empty() {
            continue;
        }
        let sw = super::files::sweep_zone(study, &zc.name, Some(&motions[z]))?;
        let inp = ZoneInputs {
            name: &zc.name,
            target: &zc.target,
            grid,
            physics: &physics,
            building,
            frames,
            motions: &motions[z],
            sweep: &sw,
            keep_going: &keep_going,
        };
        let work = tnew::ZoneWork::new(&inp, &store.units);
        let of_units =
            zone_units(s, &store, z, &work, &mine, shard.is_none()).map_err(|e| match e {
                PipelineError::Tnew(e) => stopped(e),
                e => e,
            })?;
        if shard.is_some() {
            continue;
        }
        let out = work.finish(of_units).map_err(stopped)?;
        if let Some(f) = &out.fractions {
            let line = format!(
                "zone {}: effective live-load fraction λ {}",
                zc.name,
                f.summary()
            );
            s.reporter.info(me, &line);
        }
        let line = format!(
            "zone {}: {} cases; {}",
            zc.name,
            out.cases,
            out.bands.summary()
        );
        s.reporter.info(me, &line);
        zones.push(out.tnew);
        s.pass("tnew.zone", me)?;
    }
    if let Some((k, n)) = shard {
        return Ok(StageOutcome::ShardDone { k, n });
    }
    let building_json = study.building_attr();
    let mut settings = super::physics_attrs(&physics).to_vec();
    if let Some(b) = &building_json {
        settings.push(("building", crate::store::h5::Attr::Str(b)));
    }
    let meta = TnewMeta {
        fingerprint: study.fingerprint(me)?,
        sweep_fingerprint: study.fingerprint(StageId::Sweep)?,
        motions_fingerprint: study.fingerprint(StageId::Motions)?,
        flag_codes: TNEW_FLAG_CODES,
        band_flags: BAND_FLAGS,
        lambda_flags: FRACTION_FLAGS,
        mu_static_ratio: physics.mu_static_ratio,
        settings: &settings,
    };
    let path = study.path(me.output());
    write_tnew(&path, &meta, grid, building, &zones)?;
    remove_units(study)?;
    Ok(StageOutcome::Wrote(vec![path]))
}

/// The fractions of zone `z`'s units `mine` (indices into its units): each read from its unit
/// file or computed (in parallel, each stored as it ends); all of them in order when `keep`
/// (the unsharded stage), else none.
fn zone_units(
    s: &Session,
    store: &FractionUnits,
    z: usize,
    work: &tnew::ZoneWork,
    mine: &[usize],
    keep: bool,
) -> Result<Vec<Vec<CaseFractions>>, PipelineError> {
    let me = StageId::Tnew;
    let (mut held, todo) = super::scan_units(s, me, mine, keep, |u| store.read(z, u));
    if todo.is_empty() {
        return Ok(held.into_iter().flatten().collect());
    }
    let zone = &s.study.cfg.zones[z].name;
    let line = format!(
        "zone {zone}: {} of {} units of the attached fractions to compute",
        todo.len(),
        mine.len()
    );
    s.reporter.info(me, &line);
    let dir = s.study.path(UNITS_DIR);
    std::fs::create_dir_all(&dir).map_err(|e| StoreError::io(&dir, "cannot create", e))?;
    let bar = s.reporter.progress(me, todo.len() as u64);
    let done = (todo.par_iter())
        .map(
            |&(i, u)| -> Result<(usize, Vec<CaseFractions>), PipelineError> {
                s.check_cancelled(me)?;
                let fractions = work.fractions_of(&store.units[u])?;
                store.write(z, u, &fractions)?;
                bar.inc();
                s.pass("tnew.unit", me)?;
                Ok((i, fractions))
            },
        )
        .collect::<Result<Vec<_>, _>>()?;
    bar.finish();
    for (i, fractions) in done {
        if keep {
            held[i] = Some(fractions);
        }
    }
    Ok(match keep {
        true => (held.into_iter())
            .map(|f| f.expect("read or computed"))
            .collect(),
        false => Vec::new(),
    })
}

/// `(units tnew computes, units stored for the current tnew)`: 0 units on one storey; none
/// stored before the sweep is up to date.
pub fn unit_status(study: &Study) -> Result<(usize, usize), PipelineError> {
    let store = FractionUnits::new(study)?;
    let total = store.total();
    let done = match study.state(StageId::Tnew)? {
        super::StageState::UpToDate => total,
        _ if total == 0 || study.state(StageId::Sweep)? != super::StageState::UpToDate => 0,
        _ => (0..study.cfg.zones.len())
            .flat_map(|z| (0..store.units.len()).map(move |u| (z, u)))
            .filter(|&(z, u)| matches!(store.read(z, u), Ok(Some(_))))
            .count(),
    };
    Ok((total, done))
}

/// Removes `tnew`'s unit files (after `tnew.h5` was verified, or left over from an interrupted
/// cleanup).
pub fn remove_units(study: &Study) -> Result<(), StoreError> {
    crate::store::units::remove_units(&study.path(UNITS_DIR))
}

/// `tnew`'s unit files: per case of a unit, one `f64` column (the stack's, the rigid system's
/// and the bare building's mean peaks, each the roof, every storey's shear and the overturning
/// moment; the stuck mass share; the fractions of the roof, each storey's shear, the overturning
/// moment and the code's) and one `u8` column (their flags), under an identity whose
/// `period_index` and `period_s` are the unit's `T_p` and whose `alpha_total` its total `α`.
struct FractionUnits<'a> {
    study: &'a Study,
    /// Every zone's units (the same for each zone: they follow the grid and the frames).
    units: Vec<FractionUnit>,
    fingerprint: String,
}

impl<'a> FractionUnits<'a> {
    fn new(study: &'a Study) -> Result<Self, PipelineError> {
        let me = StageId::Tnew;
        let units = fraction_units(study.grid(me)?, study.building(), study.frames());
        Ok(Self {
            study,
            units,
            fingerprint: study.fingerprint(me)?.to_string(),
        })
    }

    /// Units over every zone.
    fn total(&self) -> usize {
        self.study.cfg.zones.len() * self.units.len()
    }

    fn place(&self, z: usize, u: usize) -> (PathBuf, UnitId) {
        let zone = &self.study.cfg.zones[z].name;
        let unit = &self.units[u];
        let grid = self.study.shape.grid().expect("tnew has a grid");
        let first = unit.cases[0] % grid.cases();
        let path = (self.study.path(UNITS_DIR)).join(format!("{zone}_{u:04}.unit"));
        let id = UnitId {
            fingerprint: self.fingerprint.clone(),
            zone: zone.clone(),
            motion_index: None,
            motion: None,
            period_index: first / grid.cases_per_unit(),
            period_s: unit.period_s,
            frame: super::files::frame_label(self.study, unit.frame),
            alpha_total: Some(unit.alpha_total),
        };
        (path, id)
    }

    fn write(&self, z: usize, u: usize, fractions: &[CaseFractions]) -> Result<(), StoreError> {
        let mut c = Columns::default();
        for x in fractions {
            let mut f = Vec::new();
            for m in [&x.stack, &x.rigid, &x.bare] {
                f.push(m.roof_m);
                f.extend(&m.storey_shear);
                f.push(m.overturning);
            }
            f.push(x.share);
            let found = std::iter::once(&x.roof)
                .chain(&x.storey)
                .chain([&x.overturning, &x.code]);
            let (values, flags): (Vec<f64>, Vec<u8>) = found.map(|&(v, g)| (v, g as u8)).unzip();
            f.extend(values);
            c.f64s.push(f);
            c.u8s.push(flags);
        }
        let (path, id) = self.place(z, u);
        write_unit(&path, &id, &c)
    }

    /// The unit's fractions, `None` when no file holds them for this `tnew` (missing, or made
    /// with other inputs); a file of the wrong shape is refused as damaged.
    fn read(&self, z: usize, u: usize) -> Result<Option<Vec<CaseFractions>>, StoreError> {
        let (path, id) = self.place(z, u);
        let c = match read_unit(&path, &id)? {
            Stored::Valid(c) => c,
            Stored::Missing | Stored::Stale => return Ok(None),
        };
        let unit = &self.units[u];
        let n = self.study.frames()[unit.frame].storeys();
        let (nf, nu) = (3 * (n + 2) + 1 + (n + 3), n + 3);
        let decoded = (c.f64s.len() == unit.cases.len() && c.u8s.len() == unit.cases.len())
            .then(|| {
                (c.f64s.iter().zip(&c.u8s))
                    .map(|(f, g)| decode(f, g, n).filter(|_| f.len() == nf && g.len() == nu))
                    .collect::<Option<Vec<_>>>()
            })
            .flatten();
        decoded.map(Some).ok_or_else(|| {
            let why = format!(
                "does not hold {} cases of a {n}-storey building's attached fractions",
                unit.cases.len()
            );
            StoreError::corrupt(&path, why)
        })
    }
}

/// One case's fractions from its unit columns ([`FractionUnits`]) in a building of `n` storeys;
/// `None` when a column is short or a flag is not one.
fn decode(f: &[f64], g: &[u8], n: usize) -> Option<CaseFractions> {
    let mut at = f.iter().copied();
    let mut means = || -> Option<Means> {
        let roof_m = at.next()?;
        let storey_shear: Vec<f64> = at.by_ref().take(n).collect();
        let overturning = at.next()?;
        (storey_shear.len() == n).then_some(Means {
            roof_m,
            storey_shear,
            overturning,
        })
    };
    let (stack, rigid, bare) = (means()?, means()?, means()?);
    let share = at.next()?;
    let mut found = Vec::with_capacity(n + 3);
    for &code in g {
        found.push((at.next()?, FractionFlag::from_code(code)?));
    }
    if found.len() != n + 3 {
        return None;
    }
    Some(CaseFractions {
        stack,
        rigid,
        bare,
        share,
        roof: found[0],
        storey: found[1..=n].to_vec(),
        overturning: found[n + 1],
        code: found[n + 2],
    })
}
