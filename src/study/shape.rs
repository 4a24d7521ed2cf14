//! What a study is over: its grid of cases and the frames each case stands in (docs/model.md,
//! "A study over buildings"). A one-storey study is the study of one frame,
//! [`Frame::one_storey`], which runs the one-storey systems; a building study has the frames of
//! its `building:` section, and its stored files carry their axes. The stages, the fit, the
//! report and the design page take a study's frames, their distinct buildings and their labels
//! from here.

use super::building::{Frame, first_of_building};
use super::config::StudyConfig;
use crate::grid::{BuildingAxes, Grid};

/// A study's grid (`None` without a `grid` section) and frames (never empty).
#[derive(Debug, Clone, PartialEq)]
pub struct StudyShape {
    grid: Option<Grid>,
    building: Option<BuildingAxes>,
    frames: Vec<Frame>,
}

impl StudyShape {
    /// The shape of a validated config.
    pub fn of(cfg: &StudyConfig) -> Self {
        let building = cfg.building_axes();
        let frames = match &building {
            None => vec![Frame::one_storey()],
            Some(b) => (0..b.frame_count())
                .filter_map(|f| cfg.frame(b, f))
                .collect(),
        };
        Self {
            grid: cfg.grid.as_ref().map(|g| g.axes()),
            building,
            frames,
        }
    }

    /// The grid of cases (`None` without a `grid` section).
    pub fn grid(&self) -> Option<&Grid> {
        self.grid.as_ref()
    }

    /// A building study's axes (`storeys`, `stack_floor`); `None` on one storey, whose stored
    /// files have no frame axes.
    pub fn building(&self) -> Option<&BuildingAxes> {
        self.building.as_ref()
    }

    pub fn is_building(&self) -> bool {
        self.building.is_some()
    }

    /// The frames in stored order (storeys, then stack floor fastest); one on one storey.
    pub fn frames(&self) -> &[Frame] {
        &self.frames
    }

    /// A building study's frames; none on one storey, whose stored files name no frame.
    pub fn building_frames(&self) -> &[Frame] {
        match self.building {
            Some(_) => &self.frames,
            None => &[],
        }
    }

    /// The frames that are not an earlier one's building ([`first_of_building`]), with their
    /// stored index: what the fit counts and the report shows.
    pub fn distinct(&self) -> Vec<(usize, &Frame)> {
        let first = first_of_building(&self.frames);
        (self.frames.iter().enumerate())
            .filter(|(f, _)| first[*f] == *f)
            .collect()
    }

    /// Frame `f`'s label (`3 storeys, stack on the roof`) in a building study; `None` on one
    /// storey, whose results name no frame.
    pub fn label(&self, f: usize) -> Option<String> {
        self.is_building().then(|| self.frames[f].to_string())
    }

    /// What a message about frame `f` appends: `, 3 storeys, stack on the roof`; nothing on one
    /// storey.
    pub fn label_suffix(&self, f: usize) -> String {
        self.label(f).map_or(String::new(), |l| format!(", {l}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::StackFloor;

    fn study(extra: &str) -> StudyConfig {
        let text = format!(
            "output_dir: out\nzones:\n  - {{ name: V, target: \"is1893:zone=V,soil=I\" }}\n\
             motions:\n  seeds:\n    stochastic: {{ count: 1, seed: 1 }}\n{extra}grid:\n  \
             period_s: [0.5]\n  alpha: [[0.5]]\n  mu: [[0.2]]\n{}",
            if extra.is_empty() {
                ""
            } else {
                "  stack_floor: [1, roof, all]\n"
            }
        );
        StudyConfig::parse(
            text.as_bytes(),
            std::path::Path::new("shape.yaml"),
            std::path::Path::new("."),
        )
        .unwrap()
    }

    #[test]
    fn one_storey_is_one_unlabelled_frame() {
        let shape = StudyShape::of(&study(""));
        assert!(!shape.is_building());
        assert_eq!(shape.frames(), [Frame::one_storey()]);
        assert_eq!(shape.distinct(), [(0, &Frame::one_storey())]);
        assert_eq!(shape.label(0), None);
        assert_eq!(shape.label_suffix(0), "");
        assert!(shape.building_frames().is_empty());
    }

    #[test]
    fn the_frame_of_one_storey_is_the_building_of_one_storey() {
        let shape = StudyShape::of(&study("building: { storeys: [1, 2] }\n"));
        assert_eq!(shape.frames().len(), 6);
        assert_eq!(shape.frames()[1], Frame::one_storey());
        assert_eq!(shape.frames()[0].stack_floor, StackFloor::Floor(1));
        // On one storey floor 1, the roof and every floor are one building.
        let distinct: Vec<usize> = shape.distinct().iter().map(|(f, _)| *f).collect();
        assert_eq!(distinct, [0, 3, 4, 5]);
        assert_eq!(
            shape.label(4).as_deref(),
            Some("2 storeys, stack on the roof")
        );
        assert_eq!(shape.building_frames(), shape.frames());
        assert_eq!(shape.label_suffix(4), ", 2 storeys, stack on the roof");
    }
}
