//! Stage `shift`: the left shift of the shading buffer after a bounce,
//! G(k-1) ← G(k), G(k) ← G(k+1), so the next bounce starts from G(k+1).

use crate::shading_buffer::ShadingBuffer;
use rayon::prelude::*;

pub fn shift(buf: &mut ShadingBuffer) {
    let ShadingBuffer {
        prev,
        cur,
        next,
        scatter,
        ..
    } = buf;
    (prev, cur, next, scatter)
        .into_par_iter()
        .for_each(|(prev, cur, next, scatter)| {
            if let Some(c) = cur {
                *prev = c.p;
            }
            *cur = next.take();
            *scatter = None;
        });
}
