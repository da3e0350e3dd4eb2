#include "SwapReport.h"

#include "ReportFormat.h"

#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace cullide::bench {

namespace {

using nlohmann::json;

/// Setter names of cullide-swap-bench's switches (benchmarks/swap_bench.cpp).
const std::map<std::string, std::string> kSwitchSetters = {
    {"--gimpact-pair-culling", "`setGImpactPairCulling(true)`"},
    {"--gimpact-mesh-culling", "`setGImpactMeshCulling(true)`"},
    {"--gimpact-convex-culling", "`setGImpactConvexCulling(true)`"},
    {"--no-penetration-fallback", "`setDeepPenetrationFallback(false)`"},
    {"--sap-object-level", "`setObjectLevel(btAxisSweep3)`"},
    {"--convex-mesh-culling", "`setConvexMeshCulling(true)`"},
    {"SWAP_BENCH_CONVEX_MESH=1", "`setConvexMeshCulling(true)`"},
    {"--auto-culling-anywhere", "`setAutoCullingOnAnyDevice(true)`"},
    {"--culling auto", "every `setCulling(kind, Culling::Auto)`"},
    {"--culling on", "every `setCulling(kind, Culling::On)`"},
    {"--culling off", "every `setCulling(kind, Culling::Off)`"},
};

std::vector<std::string> words(const std::string& s) {
    std::istringstream in(s);
    std::vector<std::string> out;
    for (std::string w; in >> w;) out.push_back(w);
    return out;
}

double num(const json& row, const std::string& key) { return number(row, key).value_or(0.0); }

std::size_t whole(const json& row, const std::string& key) {
    return static_cast<std::size_t>(std::max(0.0, num(row, key)));
}

/// The rows of a run, checked: an array of objects that name their scene.
const json& rowsOf(const json& run) {
    const json& rows = run.at("rows");
    if (!rows.is_array()) throw std::runtime_error("a swap run's rows are not an array");
    for (const auto& r : rows)
        if (!r.is_object() || !r.contains("scene") || !r.at("scene").is_string())
            throw std::runtime_error("a swap row without a scene name");
    return rows;
}

/// "a of b" with both counts, or "a" alone where b is 0.
std::string ofCount(std::size_t a, std::size_t b) { return b > 0 ? count(double(a)) + " of " + count(double(b)) : count(double(a)); }

std::string commandFor(const std::string& switches, const json& rows) {
    std::string env, flags;
    for (const auto& w : words(switches)) (w.find('=') != std::string::npos ? env : flags) += w + " ";
    int steps = 0;
    for (const auto& r : rows) steps = std::max(steps, r.value("steps", 0));
    return env + "cullide-swap-bench --steps " + std::to_string(steps) + " " + flags + "--json FILE";
}

void machines(std::ostringstream& md, const std::vector<json>& results) {
    md << "## Machines\n\n| class | date (UTC) | CPU | cores | GL renderer | load before → after | commit |\n"
          "|---|---|---|---|---|---|---|\n";
    for (const auto& r : results) {
        const json& m = r.at("machine");
        const json probe = m.value("probe", json::object());
        md << "| " << m.value("class", "cpu") << (m.value("quick", false) ? " (quick run)" : "") << " | "
           << m.value("date", "") << " | " << cell(m.value("cpu", "")) << " | " << m.value("cores", 0) << " | "
           << (probe.value("renderer", "").empty() ? std::string("–") : cell(probe.value("renderer", ""))) << " | " << m.value("load_before", "") << " → "
           << m.value("load_after", "") << " | " << m.value("commit", "") << " |\n";
    }
    md << "\nThe load average is the machine's (1, 5, 15 min). The three worlds of a scene share every step's load, so "
          "their ratio holds on a busy machine better than their milliseconds do.\n\n";
}

/// The culling switches' states at the end of a row's run ("culling" in the rows of cullide-swap-bench versions
/// that record it), in CulledKind order; empty where the row has none.
std::string cullingStates(const json& row) {
    const auto it = row.find("culling");
    if (it == row.end() || !it->is_object()) return "";
    std::string out;
    for (const char* kind : {"gimpact_pair", "gimpact_mesh", "gimpact_convex", "convex_mesh"})
        out += (out.empty() ? "" : " / ") + it->value(kind, std::string("–"));
    return out;
}

/// Steps, and where fewer steps' contacts were compared (a scene whose worlds departed), those.
std::string stepsCell(const json& row) {
    const int steps = row.value("steps", 0);
    const auto compared = number(row, "compared_steps");
    if (!compared || int(*compared) >= steps) return std::to_string(steps);
    return std::to_string(steps) + " (contacts: " + count(*compared) + ")";
}

void runTable(std::ostringstream& md, const json& run) {
    const json& rows = rowsOf(run);
    const std::string switches = run.value("switches", "");
    bool states = false;
    for (const auto& r : rows) states = states || !cullingStates(r).empty();
    md << "`" << commandFor(switches, rows) << "`\n\n"
          "| scene | bodies | steps | dbvt ms | SAP ms | swap ms | ratio | narrow phase ms: dbvt / swap | pairs a step: "
          "threaded / apart | lost pairs | extra pairs | contact keys missing / extra | deepest-point difference: max / "
          "mean |"
       << (states ? " culling switches at the end: GImpact pair / GImpact mesh / GImpact convex / convex mesh |" : "")
       << "\n|---|---|---|---|---|---|---|---|---|---|---|---|---|" << (states ? "---|" : "") << "\n";
    for (const auto& r : rows) {
        const double best = std::min(num(r, "dbvt_ms"), num(r, "sap_ms"));
        md << "| " << r.at("scene").get<std::string>() << " | " << count(num(r, "bodies")) << " | "
           << stepsCell(r) << " | " << ms(num(r, "dbvt_ms")) << " | " << ms(num(r, "sap_ms")) << " | "
           << ms(num(r, "cullide_ms")) << " | **" << (best > 0 ? ratio(num(r, "cullide_ms") / best) : "–")
           << "** | " << ms(num(r, "dbvt_narrow_ms")) << " / " << ms(num(r, "cullide_narrow_ms")) << " | "
           << fixed(num(r, "threaded_pairs"), 0) << " / " << fixed(num(r, "apart_pairs"), 0) << " | "
           << ofCount(whole(r, "lost"), whole(r, "contact_pair_steps")) << " | " << count(num(r, "extra")) << " | "
           << ofCount(whole(r, "points_missing"), whole(r, "points")) << " / "
           << (r.contains("points_extra") ? count(num(r, "points_extra")) : std::string("–")) << " | "
           << fixed(num(r, "deepest_diff_max"), 4) << " / " << fixed(num(r, "deepest_diff_mean"), 4) << " |";
        if (states) md << " " << (cullingStates(r).empty() ? "–" : cullingStates(r)) << " |";
        md << "\n";
    }
    const SwapSummary s = summarizeSwapRun(run);
    md << "\n" << s.scenes << " scenes: the swap's step over the faster of Bullet's two, median "
       << ratio(s.ratioMedian) << " (" << ratio(s.ratioMin) << " on " << s.fastestScene << " to "
       << ratio(s.ratioMax) << " on " << s.slowestScene << "); lost pairs " << ofCount(s.lost, s.contactPairSteps)
       << "; contact keys missing " << ofCount(s.pointsMissing, s.points) << ", extra " << count(double(s.pointsExtra))
       << "; largest deepest-point difference "
       << fixed(s.deepestDiffMax, 4) << ".\n\n";
}

/// The runs with switches against the defaults' run of the same machine, scene by scene.
void againstDefaults(std::ostringstream& md, const json& defaults, const json& run) {
    std::map<std::string, const json*> base;
    for (const auto& r : rowsOf(defaults)) base[r.at("scene").get<std::string>()] = &r;
    std::ostringstream rows;
    for (const auto& r : rowsOf(run)) {
        const auto it = base.find(r.at("scene").get<std::string>());
        if (it == base.end()) continue;
        const json& d = *it->second;
        auto rat = [](const json& x) {
            const double best = std::min(num(x, "dbvt_ms"), num(x, "sap_ms"));
            return best > 0 ? ratio(num(x, "cullide_ms") / best) : std::string("–");
        };
        rows << "| " << r.at("scene").get<std::string>() << " | " << rat(d) << " | " << rat(r) << " | "
             << ofCount(whole(d, "lost"), whole(d, "contact_pair_steps")) << " → "
             << ofCount(whole(r, "lost"), whole(r, "contact_pair_steps")) << " | "
             << ofCount(whole(d, "points_missing"), whole(d, "points")) << " → "
             << ofCount(whole(r, "points_missing"), whole(r, "points")) << " | "
             << fixed(num(d, "deepest_diff_max"), 4) << " → " << fixed(num(r, "deepest_diff_max"), 4) << " | "
             << count(num(r, "culled_pairs")) << " / " << count(num(r, "pruned_pairs")) << " |\n";
    }
    if (rows.str().empty()) return;
    md << "Against the default switches, same machine (each column from its own run):\n\n"
          "| scene | ratio, defaults | ratio, these switches | lost pairs | contact keys missing | deepest-point "
          "difference, max | culled / pruned pairs, last step |\n|---|---|---|---|---|---|---|\n"
       << rows.str() << "\n";
}

}  // namespace

json combineSwapRuns(const json& machine, const std::vector<SwapRun>& runs) {
    json out;
    out["machine"] = machine.contains("machine") ? machine.at("machine") : machine;
    if (!out["machine"].is_object()) throw std::runtime_error("the machine description is not an object");
    out["runs"] = json::array();
    for (const auto& run : runs) {
        json r;
        r["switches"] = run.switches;
        r["rows"] = readJsonFile(run.jsonPath);
        try {
            rowsOf(r);
        } catch (const std::exception& e) {
            throw std::runtime_error(run.jsonPath + ": " + e.what());
        }
        out["runs"].push_back(std::move(r));
    }
    return out;
}

SwapSummary summarizeSwapRun(const json& run) {
    SwapSummary s;
    std::vector<std::pair<double, std::string>> ratios;
    for (const auto& r : rowsOf(run)) {
        const double best = std::min(num(r, "dbvt_ms"), num(r, "sap_ms"));
        if (best > 0) ratios.emplace_back(num(r, "cullide_ms") / best, r.at("scene").get<std::string>());
        s.lost += whole(r, "lost");
        s.contactPairSteps += whole(r, "contact_pair_steps");
        s.pointsMissing += whole(r, "points_missing");
        s.pointsExtra += whole(r, "points_extra");
        s.points += whole(r, "points");
        s.deepestDiffMax = std::max(s.deepestDiffMax, num(r, "deepest_diff_max"));
    }
    s.scenes = ratios.size();
    if (ratios.empty()) return s;
    std::sort(ratios.begin(), ratios.end());
    const std::size_t n = ratios.size();
    s.ratioMedian = n % 2 == 1 ? ratios[n / 2].first : 0.5 * (ratios[n / 2 - 1].first + ratios[n / 2].first);
    s.ratioMin = ratios.front().first;
    s.fastestScene = ratios.front().second;
    s.ratioMax = ratios.back().first;
    s.slowestScene = ratios.back().second;
    return s;
}

std::string swapSwitchesLabel(const std::string& switches) {
    std::string out;
    const std::vector<std::string> ws = words(switches);
    for (std::size_t i = 0; i < ws.size(); ++i) {
        // A flag with a value ("--culling on") is one switch.
        std::string w = ws[i];
        if (w == "--culling" && i + 1 < ws.size()) w += " " + ws[++i];
        const auto it = kSwitchSetters.find(w);
        out += (out.empty() ? "" : ", ") + (it != kSwitchSetters.end() ? it->second : "`" + w + "`");
    }
    return out.empty() ? "the default switches" : out;
}

void writeSwapPage(const std::vector<json>& input, const std::string& docPath) {
    std::vector<json> results = input;
    std::sort(results.begin(), results.end(), [](const json& a, const json& b) {
        return a.at("machine").value("class", "cpu") < b.at("machine").value("class", "cpu");
    });
    std::ostringstream md;
    md << "# The two-line swap against Bullet's pipelines\n\n"
          "<!-- Generated by scripts/bench.sh (cullide-bench-report swap) from docs/bench/swap-*.json. Do not edit: "
          "rerun the script. -->\n\n"
          "`cullide-swap-bench` (`benchmarks/swap_bench.cpp`) builds each scene three times from the same shapes: "
          "Bullet's default pipeline (`btDbvtBroadphase` + `btCollisionDispatcher`, *dbvt*), `btAxisSweep3` + "
          "`btCollisionDispatcher` (*SAP*), and the two-line swap (`CullideBroadphase` + "
          "`CullideCollisionDispatcher`, *swap*; `bullet_adapter/README.md`). It steps the three worlds in lockstep "
          "in one process: every step each world is stepped once, timed, the order rotating, and then the default "
          "world's body states are copied into the other two, so all three detect collisions on identical states. "
          "The breakable and soft-body scenes carry state of their own (fracture pieces, soft nodes): there each "
          "world runs its own simulation from the same start, and the swap's world is compared with the default's "
          "every step (a departure is reported on the bench's stderr).\n\n"
          "**Columns.** *ms*: mean step time of each world over the run (`stepSimulation`, or "
          "`performDiscreteCollisionDetection` for the `*-world` scenes, which are collision-only "
          "`btCollisionWorld`s); the first steps count, so a culler made at the first step that needs it (a GL "
          "context, shaders) weighs on a short run. *Ratio*: the swap's step over the faster of dbvt and SAP. *Narrow phase*: "
          "`dispatchAllCollisionPairs`. *Threaded*: pairs a step whose Bullet algorithm ran on the swap's "
          "narrow-phase threads; *apart*: pairs a step whose algorithm the swap skipped, their boxes farther apart "
          "than the contact breaking threshold. *Lost pairs*: object pairs with contact points after the default "
          "world's step and none after the swap's, of all pair-steps with points (soft-bodies: soft contacts the "
          "swap's world has fewer of); *extra pairs*: the reverse. Where the steps column names fewer steps for the "
          "contacts, the worlds departed (a culled path placed a point otherwise) and only the steps before were "
          "compared. *Contact keys missing*: points of the default "
          "world whose (part, triangle) key on both sides the swap's manifold of the same pair lacks, of all points "
          "of the pairs with points in both worlds. *Deepest-point difference*: |deepest point − deepest point| "
          "per such pair-step, its largest value and its mean.\n\n";
    machines(md, results);
    for (const auto& result : results) {
        const json& runs = result.at("runs");
        md << "## " << classTitle(result.at("machine").value("class", "cpu")) << "\n\n";
        const json* defaults = nullptr;
        for (const auto& run : runs)
            if (words(run.value("switches", "")).empty()) defaults = &run;
        for (const auto& run : runs) {
            md << "### " << swapSwitchesLabel(run.value("switches", "")) << "\n\n";
            runTable(md, run);
            if (defaults != nullptr && &run != defaults) againstDefaults(md, *defaults, run);
        }
    }
    md << "## Scenes\n\n| scene | what |\n|---|---|\n";
    std::map<std::string, std::string> seen;
    std::vector<std::string> order;
    for (const auto& result : results)
        for (const auto& run : result.at("runs"))
            for (const auto& r : rowsOf(run)) {
                const std::string scene = r.at("scene").get<std::string>();
                if (seen.emplace(scene, r.value("what", "")).second) order.push_back(scene);
            }
    for (const auto& scene : order) md << "| " << scene << " | " << cell(seen[scene]) << " |\n";
    md << "\n## Reproduce\n\n```sh\nscripts/bench.sh --swap      # the swap's runs only: this page and the "
          "README's headline table\nscripts/bench.sh             # every benchmark, this page included\n"
          "build-bench/benchmarks/cullide-swap-bench --steps 60 --scene tori-pile   # one scene, a table on stdout\n"
          "```\n`SWAP_STEPS` sets the steps of `scripts/bench.sh`'s swap runs; `cullide-swap-bench --help` lists the "
          "scenes and switches.\n";
    std::ofstream out(docPath);
    out << md.str();
    if (!out) throw std::runtime_error("cannot write " + docPath);
}

}  // namespace cullide::bench
