// A count of loop iterations. Lavapipe (llvmpipe) ends every loop of an
// invocation once the invocation has run 65535 loop iterations in total,
// counted over its SIMD group (8 lanes at 256 bits), and says nothing: the
// results are silently wrong. So every loop counts its iterations here. The
// short, bounded loops of the helpers only count (`work`); the trace's own
// loops stop when the ray's budget for the dispatch is spent (`step` in
// trace.wgsl, at most dirt_gpu::trace::WORK_BUDGET), and the ray is
// continued by a later dispatch.

var<private> g_work: u32;

// Counts one iteration of a bounded loop; never stops it.
fn work() -> bool {
    g_work += 1u;
    return true;
}
