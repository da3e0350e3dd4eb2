// cullide-bench-report: the report side of scripts/bench.sh.
//   cullide-bench-report combine --records results.jsonl --machine machine.json --out results.json
//   cullide-bench-report render --docs FILE.md --plots DIR --data DIR results.json...
// `combine` joins the per-process records and the machine description into one results.json; `render` writes the
// Markdown report and the gnuplot data and scripts (one results.json per machine class, cpu and/or gpu).
#include "ReportWriter.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

nlohmann::json readJson(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw std::runtime_error("cannot read " + path);
    return nlohmann::json::parse(in);
}

int usage() {
    std::fprintf(stderr, "usage: cullide-bench-report combine --records FILE.jsonl --machine FILE --out FILE\n"
                         "       cullide-bench-report render --docs FILE.md --plots DIR --data DIR RESULTS.json...\n");
    return 2;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) return usage();
    const std::string command = argv[1];
    std::string records, machine, out, docs, plots, data;
    std::vector<std::string> inputs;
    for (int i = 2; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&]() -> std::string { return i + 1 < argc ? argv[++i] : ""; };
        if (a == "--records") records = value();
        else if (a == "--machine") machine = value();
        else if (a == "--out") out = value();
        else if (a == "--docs") docs = value();
        else if (a == "--plots") plots = value();
        else if (a == "--data") data = value();
        else if (a.rfind("--", 0) == 0) return usage();
        else inputs.push_back(a);
    }
    try {
        if (command == "combine") {
            if (records.empty() || machine.empty() || out.empty()) return usage();
            nlohmann::json result;
            result["machine"] = readJson(machine);
            result["records"] = nlohmann::json::array();
            std::ifstream in(records);
            std::string line;
            while (std::getline(in, line))
                if (!line.empty()) result["records"].push_back(nlohmann::json::parse(line));
            std::ofstream o(out);
            o << result.dump(1) << '\n';
            if (!o) throw std::runtime_error("cannot write " + out);
            return 0;
        }
        if (command == "render") {
            if (docs.empty() || plots.empty() || data.empty() || inputs.empty()) return usage();
            std::vector<nlohmann::json> results;
            for (const auto& path : inputs) results.push_back(readJson(path));
            cullide::bench::ReportWriter(std::move(results), docs, plots, data).write();
            return 0;
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "cullide-bench-report: %s\n", e.what());
        return 1;
    }
    return usage();
}
