#include "Headline.h"

#include "ReportFormat.h"
#include "SwapReport.h"

#include <algorithm>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace cullide::bench {

namespace {

using nlohmann::json;

std::string peerLabel(const std::string& engine) {
    if (engine == "bullet-dbvt") return "Bullet btDbvtBroadphase + GImpact";
    if (engine == "bullet-sap") return "Bullet btAxisSweep3 + GImpact";
    if (engine == "fcl") return "FCL OBBRSS";
    if (engine == "fcl-aabb") return "FCL AABB";
    return engine;
}

std::string sceneLabel(const std::string& scene) {
    if (scene == "env1") return "env1, deforming open cylinders";
    if (scene == "env2") return "env2, deforming tori";
    if (scene == "env3") return "env3, bunny through the dragon, rigid";
    if (scene == "env3-deform") return "env3, deforming bunny through the dragon";
    return scene;
}

const json* sideRecord(const json& results, const std::string& scene, const std::string& engine) {
    for (const auto& r : results.at("records"))
        if (r.value("tag", "") == "side" && r.value("scene", "") == scene && r.value("engine", "") == engine &&
            r.contains("ms"))
            return &r;
    return nullptr;
}

double medianOf(const json& r) { return r.at("ms").at("median").get<double>(); }

/// One row: a label and, per machine class, the cell text ("–" where the class has no figure).
struct Row {
    std::string label;
    std::map<std::string, std::string> cells;
    std::string page;
};

void cullerRows(const std::vector<json>& benchResults, std::vector<Row>& rows) {
    for (const std::string scene : {"env1", "env2", "env3", "env3-deform"}) {
        Row row{"", {}, "[benchmarks](docs/benchmarks.md)"};
        std::string sizes;
        for (const auto& results : benchResults) {
            const std::string cls = results.at("machine").value("class", "cpu");
            const json* mine = sideRecord(results, scene, "cullide");
            if (mine == nullptr) continue;
            if (sizes.empty())
                sizes = count(mine->value("objects", 0.0)) + " objects, " + count(mine->value("triangles", 0.0)) +
                        " triangles";
            const json* peer = nullptr;
            for (const auto& e : peerEngines()) {
                const json* p = sideRecord(results, scene, e);
                if (p != nullptr && (peer == nullptr || medianOf(*p) < medianOf(*peer))) peer = p;
            }
            std::string text = ms(medianOf(*mine)) + " ms";
            if (peer != nullptr)
                text += " = **" + ratio(medianOf(*mine) / medianOf(*peer)) + "** (" +
                        peerLabel(peer->value("engine", "")) + ": " + ms(medianOf(*peer)) + " ms)";
            row.cells[cls] = text;
        }
        row.label = "Culler, " + sceneLabel(scene) + (sizes.empty() ? "" : " (" + sizes + ")") +
                    ": median ms per frame, against the fastest peer";
        rows.push_back(std::move(row));
    }
    Row missed{"Culler, reliable mode: exact triangle pairs missed over every side-by-side frame", {},
               "[benchmarks](docs/benchmarks.md)"};
    for (const auto& results : benchResults) {
        double miss = 0, exact = 0;
        bool any = false;
        for (const auto& r : results.at("records"))
            if (r.value("tag", "") == "side" && r.value("engine", "") == "cullide" &&
                r.contains("missed_triangle_pairs")) {
                any = true;
                miss += number(r, "missed_triangle_pairs").value_or(0.0);
                exact += number(r, "exact_triangle_pairs").value_or(0.0);
            }
        if (any) missed.cells[results.at("machine").value("class", "cpu")] = count(miss) + " of " + count(exact);
    }
    rows.push_back(std::move(missed));
}

const json* defaultsRun(const json& swap) {
    for (const auto& run : swap.at("runs"))
        if (run.value("switches", "").find_first_not_of(' ') == std::string::npos) return &run;
    return nullptr;
}

std::string ratioRange(const SwapSummary& s) {
    return "median **" + ratio(s.ratioMedian) + "** over " + std::to_string(s.scenes) + " scenes (" +
           ratio(s.ratioMin) + " " + s.fastestScene + " … " + ratio(s.ratioMax) + " " + s.slowestScene + ")";
}

void swapRows(const std::vector<json>& swapResults, std::vector<Row>& rows) {
    const std::string page = "[swap](docs/swap.md)";
    Row speed{"Two-line swap, default switches: step time over the faster of Bullet's two pipelines", {}, page};
    Row contacts{"Two-line swap, default switches: object pairs with contact points lost; contact keys missing", {},
                 page};
    Row breakable{"Two-line swap, default switches: the breakable scene's step, against the faster of Bullet's "
                  "pipelines",
                  {}, page};
    std::vector<Row> switched;  // one per set of switches, in the order of the runs
    for (const auto& swap : swapResults) {
        const std::string cls = swap.at("machine").value("class", "cpu");
        if (const json* d = defaultsRun(swap)) {
            const SwapSummary s = summarizeSwapRun(*d);
            speed.cells[cls] = ratioRange(s);
            contacts.cells[cls] = count(double(s.lost)) + " of " + count(double(s.contactPairSteps)) + "; " +
                                  count(double(s.pointsMissing)) + " of " + count(double(s.points));
            for (const auto& r : d->at("rows"))
                if (r.value("scene", "") == "breakable") {
                    const double best = std::min(r.value("dbvt_ms", 0.0), r.value("sap_ms", 0.0));
                    if (best > 0)
                        breakable.cells[cls] = ms(r.value("cullide_ms", 0.0)) + " ms = **" +
                                               ratio(r.value("cullide_ms", 0.0) / best) + "** (" + ms(best) + " ms)";
                }
        }
        for (const auto& run : swap.at("runs")) {
            if (&run == defaultsRun(swap)) continue;
            const std::string label = "Two-line swap with " + swapSwitchesLabel(run.value("switches", "")) +
                                      ": step time over the faster of Bullet's pipelines; contact keys missing; "
                                      "largest deepest-point difference";
            auto it = std::find_if(switched.begin(), switched.end(), [&](const Row& r) { return r.label == label; });
            if (it == switched.end()) it = switched.insert(switched.end(), Row{label, {}, page});
            Row& row = *it;
            const SwapSummary s = summarizeSwapRun(run);
            row.cells[cls] = ratioRange(s) + "; " + count(double(s.pointsMissing)) + " of " +
                             count(double(s.points)) + "; " + fixed(s.deepestDiffMax, 3);
        }
    }
    rows.push_back(std::move(speed));
    rows.push_back(std::move(contacts));
    rows.push_back(std::move(breakable));
    for (auto& row : switched) rows.push_back(std::move(row));
}

}  // namespace

std::string headlineTable(const std::vector<json>& benchResults, const std::vector<json>& swapResults) {
    std::set<std::string> classes;
    for (const auto& r : benchResults) classes.insert(r.at("machine").value("class", "cpu"));
    for (const auto& r : swapResults) classes.insert(r.at("machine").value("class", "cpu"));
    std::vector<Row> rows;
    cullerRows(benchResults, rows);
    swapRows(swapResults, rows);
    std::ostringstream md;
    md << "| figure |";
    for (const auto& c : classes) md << " " << classTitle(c) << " |";
    md << " page |\n|---|";
    for (std::size_t i = 0; i < classes.size(); ++i) md << "---|";
    md << "---|\n";
    for (const auto& row : rows) {
        md << "| " << cell(row.label) << " |";
        for (const auto& c : classes) {
            const auto it = row.cells.find(c);
            md << " " << (it != row.cells.end() ? cell(it->second) : "–") << " |";
        }
        md << " " << row.page << " |\n";
    }
    md << "\nMachines, commits and dates: the pages' own tables. Each ratio compares runs made in one process or one "
          "benchmark run on the same machine.\n";
    return md.str();
}

void replaceMarkedBlock(const std::string& path, const std::string& name, const std::string& text) {
    std::ifstream in(path);
    if (!in) throw std::runtime_error("cannot read " + path);
    std::vector<std::string> lines;
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    const std::string begin = "<!-- " + name + ":begin", end = "<!-- " + name + ":end -->";
    std::size_t b = lines.size(), e = lines.size();
    for (std::size_t i = 0; i < lines.size(); ++i) {
        if (b == lines.size() && lines[i].find(begin) != std::string::npos) b = i;
        else if (b != lines.size() && lines[i].find(end) != std::string::npos) {
            e = i;
            break;
        }
    }
    if (b == lines.size() || e == lines.size())
        throw std::runtime_error(path + ": no '" + begin + "' line followed by a '" + end + "' line");
    std::ostringstream out;
    for (std::size_t i = 0; i <= b; ++i) out << lines[i] << '\n';
    out << text;
    if (!text.empty() && text.back() != '\n') out << '\n';
    for (std::size_t i = e; i < lines.size(); ++i) out << lines[i] << '\n';
    std::ofstream o(path);
    o << out.str();
    if (!o) throw std::runtime_error("cannot write " + path);
}

}  // namespace cullide::bench
