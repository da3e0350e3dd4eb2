// cullide-bench-report: the report side of scripts/bench.sh.
//   cullide-bench-report combine --records results.jsonl --machine machine.json --out results.json
//   cullide-bench-report render --docs FILE.md --plots DIR --data DIR results.json...
//   cullide-bench-report swap-combine --machine machine.json --out swap.json --run SWITCHES FILE [--run SWITCHES FILE]...
//   cullide-bench-report swap --docs FILE.md swap.json...
//   cullide-bench-report headline --readme README.md [--swap swap.json]... results.json...
// `combine` joins the per-process records and the machine description into one results.json; `render` writes the
// Markdown report (docs/benchmarks.md) and the gnuplot data and scripts (one results.json per machine class, cpu
// and/or gpu). `swap-combine` joins cullide-swap-bench runs (the file each --json wrote, with the switches it was
// given: its flags, NAME=VALUE for an environment switch, "" for the defaults) and the machine description into one
// swap results file; `swap` writes docs/swap.md from those (one per machine class). `headline` rewrites the README's
// table of headline figures (between its "<!-- headline:begin" and "<!-- headline:end -->" lines) from the same
// results files.
#include "Headline.h"
#include "ReportFormat.h"
#include "ReportWriter.h"
#include "SwapReport.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

int usage() {
    std::fprintf(stderr,
                 "usage: cullide-bench-report combine --records FILE.jsonl --machine FILE --out FILE\n"
                 "       cullide-bench-report render --docs FILE.md --plots DIR --data DIR RESULTS.json...\n"
                 "       cullide-bench-report swap-combine --machine FILE --out FILE --run SWITCHES SWAP.json...\n"
                 "       cullide-bench-report swap --docs FILE.md SWAP-RESULTS.json...\n"
                 "       cullide-bench-report headline --readme FILE.md [--swap SWAP-RESULTS.json]... "
                 "RESULTS.json...\n");
    return 2;
}

void writeJson(const nlohmann::json& j, const std::string& path) {
    std::ofstream o(path);
    o << j.dump(1) << '\n';
    if (!o) throw std::runtime_error("cannot write " + path);
}

}  // namespace

int main(int argc, char** argv) {
    using cullide::bench::readJsonFile;
    if (argc < 2) return usage();
    const std::string command = argv[1];
    std::string records, machine, out, docs, plots, data, readme;
    std::vector<std::string> inputs, swaps;
    std::vector<cullide::bench::SwapRun> runs;
    for (int i = 2; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&]() -> std::string { return i + 1 < argc ? argv[++i] : ""; };
        if (a == "--records") records = value();
        else if (a == "--machine") machine = value();
        else if (a == "--out") out = value();
        else if (a == "--docs") docs = value();
        else if (a == "--plots") plots = value();
        else if (a == "--data") data = value();
        else if (a == "--readme") readme = value();
        else if (a == "--swap") swaps.push_back(value());
        else if (a == "--run") {
            if (i + 2 >= argc) return usage();
            const std::string switches = argv[++i];
            runs.push_back({switches, argv[++i]});
        } else if (a.rfind("--", 0) == 0) return usage();
        else inputs.push_back(a);
    }
    try {
        if (command == "combine") {
            if (records.empty() || machine.empty() || out.empty()) return usage();
            nlohmann::json result;
            result["machine"] = readJsonFile(machine);
            result["records"] = nlohmann::json::array();
            std::ifstream in(records);
            std::string line;
            while (std::getline(in, line))
                if (!line.empty()) result["records"].push_back(nlohmann::json::parse(line));
            writeJson(result, out);
            return 0;
        }
        if (command == "render") {
            if (docs.empty() || plots.empty() || data.empty() || inputs.empty()) return usage();
            std::vector<nlohmann::json> results;
            for (const auto& path : inputs) results.push_back(readJsonFile(path));
            cullide::bench::ReportWriter(std::move(results), docs, plots, data).write();
            return 0;
        }
        if (command == "swap-combine") {
            if (machine.empty() || out.empty() || runs.empty() || !inputs.empty()) return usage();
            writeJson(cullide::bench::combineSwapRuns(readJsonFile(machine), runs), out);
            return 0;
        }
        if (command == "swap") {
            if (docs.empty() || inputs.empty()) return usage();
            std::vector<nlohmann::json> results;
            for (const auto& path : inputs) results.push_back(readJsonFile(path));
            cullide::bench::writeSwapPage(results, docs);
            return 0;
        }
        if (command == "headline") {
            if (readme.empty() || (inputs.empty() && swaps.empty())) return usage();
            std::vector<nlohmann::json> bench, swap;
            for (const auto& path : inputs) bench.push_back(readJsonFile(path));
            for (const auto& path : swaps) swap.push_back(readJsonFile(path));
            cullide::bench::replaceMarkedBlock(readme, "headline", cullide::bench::headlineTable(bench, swap));
            return 0;
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "cullide-bench-report: %s\n", e.what());
        return 1;
    }
    return usage();
}
