// The GL latency probe's dispatch (plugin/src/gl/GlLatency.cpp, measureGlLatency): one invocation adds 1 to a word,
// so that each dispatch depends on the one before it through the buffer (a barrier between them), as the levels'
// chained dispatches do.
layout(local_size_x = 1) in;
layout(std430, binding = CULLIDE_SSBO_COUNTERS) buffer Word { uint word[]; };

void main() { word[0] = word[0] + 1u; }
