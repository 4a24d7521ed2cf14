//! Where the study leaves its model: the share of cases whose stack would start to rock
//! (`sweep.h5`'s `rocks_stack`, with `grid.aspect`; docs/model.md, "Rocking: when a case leaves
//! the model").

use super::super::{PipelineError, Study};
use super::text::num;
use crate::render::page::{Section, para, table_with_id};

/// The section, when the config gives the blocks' ratios (`None` otherwise).
pub(super) fn rocking_section(study: &Study) -> Result<Option<Section>, PipelineError> {
    let Some(aspect) = study.aspect() else {
        return Ok(None);
    };
    // The frames to show, with their stored index (a building's repeats left out).
    let shown: Vec<(usize, String)> = (study.shape.distinct().into_iter())
        .map(|(f, _)| (f, study.shape.label(f).unwrap_or("one storey".into())))
        .collect();
    let frames = study.frames().len();
    let mut rows = Vec::new();
    for zc in &study.cfg.zones {
        let z = super::super::files::sweep_zone(study, &zc.name, None)?;
        let Some(rocks) = &z.rocks_stack else {
            return Err(crate::store::StoreError::corrupt(
                &study.path("sweep.h5"),
                format!(
                    "zone_{}: rocks_stack is missing (the config gives grid.aspect)",
                    zc.name
                ),
            )
            .into());
        };
        let motions = z.motions.len();
        // [motion, (storeys, stack_floor,) case…]: the frame axes flattened, then the cases.
        let per_motion = rocks.len() / motions.max(1);
        let cases = per_motion / frames;
        let flat: Vec<u8> = rocks.iter().copied().collect();
        for (f, frame) in &shown {
            let (mut runs, mut any) = (0usize, vec![false; cases]);
            for m in 0..motions {
                let at = m * per_motion + f * cases;
                for (c, &r) in flat[at..at + cases].iter().enumerate() {
                    runs += usize::from(r);
                    any[c] |= r == 1;
                }
            }
            let some = any.iter().filter(|&&a| a).count();
            let share = |k: usize, of: usize| {
                format!("{:.1} % ({k} of {of})", 100.0 * k as f64 / of as f64)
            };
            rows.push(vec![
                zc.name.clone(),
                frame.clone(),
                share(runs, cases * motions),
                share(some, cases),
            ]);
        }
    }
    let body = para(&format!(
        "The paper's model lets the blocks slide, never rock. With the blocks' width over height \
         (grid.aspect: {}, bottom block first; one footprint width for the whole stack), the \
         sweep flags every case and motion in which some block, or a group of stuck blocks, \
         would start to rock (docs/model.md, \"Rocking: when a case leaves the model\"): there \
         the sliding-only results are outside their model. Shares over the grid's cases \
         (sweep.h5, rocks_stack), per zone and frame: of the case–motion runs, and of the cases \
         that rock under at least one motion.",
        aspect
            .iter()
            .map(|a| num(*a))
            .collect::<Vec<_>>()
            .join(", ")
    )) + &table_with_id(
        "rocking",
        &[
            "zone",
            "frame",
            "runs that rock",
            "cases that rock under some motion",
        ],
        &rows,
    );
    Ok(Some(Section::new(
        "rocking",
        "Where the stacks would rock",
        body,
    )))
}
