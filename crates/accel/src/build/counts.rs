//! The counts a build reports about its input (kept, degenerate and out-of-range triangles,
//! skipped and flattened instances), without building: for reports that print them and trace
//! no ray (`aperture info`).

use super::check::{check_mesh, world_degenerate, Checked};
use super::count_checked;
use super::placement::{placement, FrameHints, Placement};
use crate::structure::Accel;
use crate::types::{AccelStats, InstanceInput, MeshInput};
use rayon::prelude::*;

impl Accel {
    /// The input counts of [`AccelStats`] that [`Accel::build_frame`] with these arguments
    /// would report (`degenerate_triangles`, `unique_triangles`, `invalid_index_triangles`,
    /// `skipped_instances`, `drawn_triangles`, `flattened_instances`), equal to its, without
    /// building anything; the structure's sizes and build time stay 0.
    pub fn input_counts(
        meshes: &[MeshInput<'_>],
        instances: &[InstanceInput],
        hints: FrameHints<'_>,
    ) -> AccelStats {
        let Placement {
            uses,
            flat,
            skipped,
            ..
        } = placement(meshes, instances, &hints);
        let mut stats = AccelStats {
            skipped_instances: skipped,
            flattened_instances: flat.len(),
            ..AccelStats::default()
        };
        let checked: Vec<Checked> = meshes.par_iter().map(|m| check_mesh(m, false)).collect();
        count_checked(&mut stats, &checked, &uses);
        stats.degenerate_triangles += flat
            .par_iter()
            .map(|(_, inst)| world_degenerate(&meshes[inst.mesh as usize], &inst.world_from_object))
            .sum::<usize>();
        stats
    }
}
