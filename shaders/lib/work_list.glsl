// Per-item work that continues over a chain of indirect dispatches, packed so that every
// invocation of a dispatch has an item: lavapipe runs an 8-wide SIMD group until its last lane
// finishes, and estimators with heavy-tailed work (SMS's Bernoulli trials) leave most lanes
// idle otherwise. Dispatch d reads list d % 2 (length work_count[d % 3]) and appends the items
// it leaves unfinished to list (d + 1) % 2 (length work_count[(d + 1) % 3]); its first
// invocation clears work_count[(d + 2) % 3], which dispatch d + 1 appends to. The C++ side is
// gpu::WorkList (core/gpu/WorkList.h): counts zeroed and arguments (1, 1, 1) before the chain.
#ifndef LOOM_WORK_LIST_GLSL
#define LOOM_WORK_LIST_GLSL

#define WORK_LIST_GROUP 64u  // invocations per workgroup of a list dispatch (8 x 8)

layout(std430) buffer WorkListCounts { uint work_count[3]; };
// Indirect dispatch arguments, indexed like work_count: max(1, ceil(length / WORK_LIST_GROUP))
// groups, so that a dispatch always has an invocation 0 to clear the set after the next.
layout(std430) buffer WorkListArgs { uvec4 work_args[3]; };
// x: list 0, y: list 1.
layout(std430) buffer WorkListItems { uvec2 work_items[]; };

// Appends item to the list that dispatch `dispatch` fills (dispatch 0: the kernel before the
// chain).
void work_list_append(uint dispatch, uint item) {
    uint counter = dispatch % 3u;
    uint slot = atomicAdd(work_count[counter], 1u);
    if (dispatch % 2u == 0u) work_items[slot].x = item;
    else work_items[slot].y = item;
    if (slot > 0u && slot % WORK_LIST_GROUP == 0u) atomicAdd(work_args[counter].x, 1u);
}

// The item of invocation i (i = group * WORK_LIST_GROUP + local index) in dispatch d, false
// when i is past the list's end. Call once per invocation, before any append.
bool work_list_item(uint d, uint i, out uint item) {
    if (i == 0u) {
        work_count[(d + 2u) % 3u] = 0u;
        work_args[(d + 2u) % 3u] = uvec4(1u);
    }
    item = 0u;
    if (i >= work_count[d % 3u]) return false;
    item = d % 2u == 0u ? work_items[i].x : work_items[i].y;
    return true;
}

#endif
