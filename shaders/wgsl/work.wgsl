// A work budget for loops. Lavapipe (llvmpipe) ends every loop of an
// invocation once the invocation has run 65535 loop iterations in total,
// counted over its SIMD group (8 lanes at 256 bits), and says nothing: the
// results are silently wrong. So every loop of the trace counts its
// iterations here and stops when the budget is spent; the ray is then marked
// unfinished and the host finishes it with the CPU reference (same bits).
// 7000 x 8 lanes stays under 65535 with room for the loops' exits.
const WORK_BUDGET: u32 = 7000u;

var<private> g_work: u32;

// Counts one loop iteration; false once the budget is spent.
fn work() -> bool {
    g_work += 1u;
    return g_work <= WORK_BUDGET;
}
