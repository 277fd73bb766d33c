// ReservoirSplatTemporal's scatter buffers (Liu et al. 2025, Sec. 4.2): one splat record per
// previous pixel, per current pixel the number of splats that landed and the start of its range
// in the index list, and the counters behind the pass's stats. Sizes: ReservoirSplatTemporal.cpp.
#ifndef LOOM_PASSES_RESERVOIR_SPLAT_BUFFERS_GLSL
#define LOOM_PASSES_RESERVOIR_SPLAT_BUFFERS_GLSL

// SplatRecord.dst for a previous pixel whose sample did not land: no sample (empty reservoir or
// no history), projected behind the camera or off the film, or x1 occluded in this frame.
const uint SPLAT_EMPTY = 0xFFFFFFFFu;
const uint SPLAT_OFF_SCREEN = 0xFFFFFFFEu;
const uint SPLAT_OCCLUDED = 0xFFFFFFFDu;

struct SplatRecord {
    uint dst;      // the current pixel it landed in (index), or SPLAT_*
    uint slot;     // its rank among the splats of dst (atomic counting order)
    vec2 dst_off;  // subpixel film offset in dst
    uint prim;     // x1: triangle and barycentrics, kept
    float J;       // |d film_here / d film_prev| (Eq. 15-16)
    vec2 bary;
};

// Records per previous pixel: one per multi-splat time partition (ReservoirSplatTemporal's
// timePartitions is at most this); record index = pixel * MAX_TIME_PARTITIONS + partition.
const uint MAX_TIME_PARTITIONS = 4u;

layout(std430) buffer SplatRecords { SplatRecord splat_records[]; };
layout(std430) buffer SplatRanges { uvec2 splat_ranges[]; };  // x count, y first list index
layout(std430) buffer SplatLists { uint splat_lists[]; };     // source record indices

layout(std430) buffer SplatCounters {
    uint splat_sources;         // splats attempted: previous samples (times the time partitions)
    uint splat_landed;
    uint splat_occluded;
    uint splat_off_screen;      // behind the camera or off the film
    uint splat_allocated;       // list entries handed out (the atomic range allocation)
    uint splat_resampled;       // list entries the resampling consumed
    uint splat_pixels_reached;  // current pixels at least one splat landed in
    uint splat_max_per_pixel;
    uint splat_reverse_attempts;  // canonical samples reverse-splatted
    uint splat_reverse_success;   // ... whose reverse splat is a valid prior-frame sample
    uint splat_dropped;           // list entries beyond the per-pixel cap (must stay 0)
    uint splat_pixels;            // current pixels resampled
    uint splat_not_area;          // pixels whose reservoirs are not Area ReSTIR's (no reuse)
    uint splat_backup_attempts;   // scatter_backup: backup samples copied here
    uint splat_backup_success;    // ... whose shift succeeded
};

#endif
