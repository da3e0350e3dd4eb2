// Renders docs/benchmarks.md and the gnuplot data and scripts of its plots from results.json files (one per
// machine class: "cpu" = software GL, "gpu" = hardware GL). Every number in the document comes from those files.
#pragma once

#include <nlohmann/json.hpp>

#include <sstream>
#include <string>
#include <vector>

namespace cullide::bench {

class ReportWriter {
public:
    /// `results`: results.json documents ({"machine": {...}, "records": [...]}), at most one per class.
    /// `plotDir`: where the PNGs will be (the document links them relative to its own directory);
    /// `dataDir`: where the .dat and .gp files go (gnuplot writes the PNGs into plotDir).
    ReportWriter(std::vector<nlohmann::json> results, std::string docPath, std::string plotDir, std::string dataDir);

    /// Writes the document and the plot scripts. Throws std::runtime_error on I/O errors.
    void write();

private:
    struct Class {
        std::string name;  ///< cpu | gpu
        nlohmann::json machine;
        std::vector<nlohmann::json> records;
    };

    void machines();
    void targets();
    void sideBySide(const Class& c);
    void sweep(const Class& c);
    void scaling(const Class& c);
    void memory(const Class& c);
    void gpuLevels(const Class& c);
    void threads(const Class& c);
    void gpuComparison();
    void plotSide(const Class& c);
    void plotSweep(const Class& c);
    void plotScaling(const Class& c, const std::string& tag, const std::string& param, const std::string& xlabel);

    const nlohmann::json* find(const Class& c, const std::string& tag, const std::string& scene,
                               const std::string& engine) const;
    std::vector<std::string> scenes(const Class& c, const std::string& tag) const;
    /// Fastest peer (Bullet / FCL) of a side-by-side scene; null when none ran.
    const nlohmann::json* bestPeer(const Class& c, const std::string& scene, bool gimpactOnly) const;
    std::string image(const std::string& file) const;
    void writeFile(const std::string& name, const std::string& text) const;

    std::vector<Class> m_classes;
    std::string m_docPath, m_plotDir, m_dataDir;
    std::ostringstream m_md;
};

}  // namespace cullide::bench
