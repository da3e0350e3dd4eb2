#include "FrameLog.h"

#include <algorithm>
#include <cstdio>

namespace cullide::demo {

void writeCsvHeader(std::ostream& out) {
    out << "frame,path,culled_pairs,pruned_pairs,objects,triangles,prepass_objects,prepass_groups,levels,pcs_objects,"
           "pcs_triangles,candidate_pairs,triangle_pairs,broadphase_pairs,contacts,new_pieces,prepass_ms,gpu_levels_ms,"
           "exact_ms,cull_ms,narrowphase_ms,solver_ms,fracture_ms,frame_ms,missed\n";
}

void writeCsvRow(std::ostream& out, const FrameRecord& r) {
    char ms[256];
    std::snprintf(ms, sizeof ms, "%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f", r.prepassMs, r.gpuLevelsMs, r.exactMs,
                  r.cullMs, r.narrowphaseMs, r.solverMs, r.fractureMs, r.frameMs);
    out << r.frame << ',' << r.path << ',' << r.culledPairs << ',' << r.prunedPairs << ',' << r.objects << ','
        << r.triangles << ',' << r.prepassObjects << ',' << r.prepassGroups << ',' << r.levels << ',' << r.pcsObjects
        << ',' << r.pcsTriangles << ',' << r.candidatePairs << ',' << r.trianglePairs << ','
        << r.broadphasePairs << ',' << r.contacts << ',' << r.newPieces << ',' << ms << ',';
    if (r.missed >= 0) out << r.missed;
    out << '\n';
}

Figures figuresOf(const std::vector<FrameRecord>& records, double FrameRecord::*column) {
    Figures f;
    if (records.empty()) return f;
    std::vector<double> v;
    v.reserve(records.size());
    for (const FrameRecord& r : records) v.push_back(r.*column);
    std::sort(v.begin(), v.end());
    f.median = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
    f.worst = v.back();
    double sum = 0;
    for (double x : v) sum += x;
    f.mean = sum / double(v.size());
    return f;
}

}  // namespace cullide::demo
