// The tracer's baseline variant (SSE2, every x86-64 CPU); see tracer_isa.h.
#define PTC_TRACE_NS sse2
#include "bvh/tracer_kernel.h"
