//! Writes the film to the output file, through the output sink ([`crate::film::write_output`]).

use bevy_ecs::prelude::*;

use crate::ecs::resources::{Accumulation, Output};

/// Writes the image when a pass has finished: after every pass in live preview, otherwise only
/// once the film is complete. The write is atomic; a failure is recorded, never a panic.
pub fn write_image(acc: Res<Accumulation>, mut output: ResMut<Output>) {
    if !acc.is_changed() || acc.film.samples == 0 {
        return;
    }
    if !(acc.complete || output.every_pass) {
        return;
    }
    let Some(path) = output.path.clone() else {
        return;
    };
    match acc.film.write(&path) {
        Ok(()) => {
            output.writes += 1;
            output.last_error = None;
        }
        Err(e) => output.last_error = Some(format!("{}: cannot write image: {e}", path.display())),
    }
}
