//! A frame's files: the grids of the bodies and of the contacts (one VTU file per body and
//! per pair, written from the frame's grid through a split plan), the frame's multiblock
//! file naming them, and the contact tables.

use std::sync::Arc;
use std::time::Instant;

use super::StepWriter;
use crate::Result;
use crate::model::Model;
use crate::output::pvd::PvdEntry;
use crate::output::vtm::VtmBlock;
use crate::output::writer::Content;
use crate::output::{Grid, SplitPlan};
use crate::post::{StepInfo, step_grids};
use crate::run::folder::RunFile;
use crate::solver::state::StepResult;

impl<F: FnMut(&Model, &StepResult) -> Result<()>> StepWriter<'_, '_, F> {
    /// Queues the files of a state at pseudo-time `time` (each complete or absent once
    /// written; not yet listed anywhere): with `fields` its VTU and contact CSV files;
    /// returns its history row.
    pub(super) fn write_step_files(
        &mut self,
        step: &StepResult,
        time: f64,
        fields: bool,
    ) -> Result<Vec<f64>> {
        let (mut post, mut vtu) = (0.0, 0.0);
        let start = Instant::now();
        let mut entries = Vec::new();
        if self.vtu && fields {
            let info = StepInfo {
                step: step.step,
                time,
                load_factor: step.load_factor,
            };
            let t = Instant::now();
            let (bodies, interface) =
                step_grids(self.model, &self.points, &self.interface, step, info);
            post += t.elapsed().as_secs_f64();
            let t = Instant::now();
            // The grids are made while the thread writes the last frame's (it would idle
            // while they are made after it): at most two frames' grids are in memory.
            self.out.records.make_room()?;
            self.queue_frame(step.step, bodies, interface)?;
            entries.push(frame_entry(step.step, time));
            vtu += t.elapsed().as_secs_f64();
        }
        let tables = if fields {
            self.interface.fretting_tables(self.model, step.solution)
        } else {
            Vec::new()
        };
        for (pair, table) in self.model.interface.pairs.iter().zip(tables) {
            let file = RunFile::Contact(&pair.name, step.step);
            self.out
                .records
                .queue(self.folder.path(file)?, Content::Csv(table));
        }
        self.tables
            .fretting
            .record(self.model, &self.interface, step, time)?;
        let row = self.row(step, time)?;
        self.out.series.extend(entries);
        tracing::debug!(
            step = step.step,
            post,
            vtu,
            rest = start.elapsed().as_secs_f64() - post - vtu,
            "output seconds (body recovery, VTU files queued, contact tables)"
        );
        Ok(row)
    }

    /// Queues the VTU files of output frame `step` (the grids of its `bodies` and of its
    /// `interface`, if the model has one: each cell in one file, see [`Self::queue_parts`])
    /// and the frame's multiblock file naming them.
    fn queue_frame(&mut self, step: usize, bodies: Grid, interface: Option<Grid>) -> Result<()> {
        let model = self.model;
        let cells: Vec<u32> = model.continuum.cells.iter().map(|c| c.body).collect();
        let names = model.bodies.iter().map(String::as_str);
        let mut plan = self.splits[0].take();
        let body_block = self.queue_parts(
            ("bodies", bodies),
            (&cells, &mut plan),
            names,
            RunFile::Bodies(step),
            |k| RunFile::Body(step, k),
        )?;
        self.splits[0] = plan;
        let mut blocks = vec![body_block];
        if let Some(interface) = interface {
            let cells: Vec<u32> = model.interface.elements.iter().map(|e| e.pair).collect();
            let names = model.interface.pairs.iter().map(|p| p.name.as_str());
            let mut plan = self.splits[1].take();
            blocks.push(self.queue_parts(
                ("contacts", interface),
                (&cells, &mut plan),
                names,
                RunFile::Interface(step),
                |k| RunFile::Pair(step, k),
            )?);
            self.splits[1] = plan;
        }
        let path = self.folder.path(RunFile::Frame(step))?;
        self.out.records.queue(path, Content::Vtm(blocks));
        Ok(())
    }

    /// Queues the cells of `grid`, each in one file: as `whole` when they are all one part's,
    /// else each part's cells (`part[c]` the part of cell c) as `part_file(k)` (k 1-based), so
    /// a frame's output grows with the model, not with the model times its parts. The parts'
    /// files share the grid and are written from it through `plan` (no copy of the grid per
    /// part, on the writer thread). `plan` is the division of the last frame's grid, made
    /// here if there is none that fits. Returns
    /// the block `name` of the frame's multiblock file that lists the files by the parts'
    /// names.
    fn queue_parts<'n>(
        &mut self,
        (name, grid): (&str, Grid),
        (part, plan): (&[u32], &mut Option<Arc<SplitPlan>>),
        parts: impl ExactSizeIterator<Item = &'n str>,
        whole: RunFile,
        part_file: impl Fn(usize) -> RunFile<'static>,
    ) -> Result<VtmBlock> {
        let mut datasets = Vec::new();
        if parts.len() == 1 {
            datasets.extend(parts.map(|n| (n.to_string(), whole.name().into())));
            self.out
                .records
                .queue(self.folder.path(whole)?, Content::Vtu(grid));
        } else {
            let fitting = plan.take().filter(|p| grid.fits(p));
            let division = fitting.unwrap_or_else(|| Arc::new(grid.split_plan(part, parts.len())));
            let grid = Arc::new(grid);
            for (k, part_name) in parts.enumerate() {
                let file = part_file(k + 1);
                let content = Content::VtuPart(grid.clone(), division.clone(), k);
                self.out.records.queue(self.folder.path(file)?, content);
                datasets.push((part_name.to_string(), file.name().into()));
            }
            *plan = Some(division);
        }
        Ok(VtmBlock {
            name: name.into(),
            datasets,
        })
    }
}

/// The entry of output frame `step` in the series at pseudo-time `time`: its multiblock
/// file, which names the frame's bodies and contact pairs.
pub(super) fn frame_entry(step: usize, time: f64) -> PvdEntry {
    PvdEntry {
        time,
        part: 0,
        name: "model".into(),
        file: RunFile::Frame(step).name().into(),
    }
}
