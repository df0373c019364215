#pragma once
// report.html: one self-contained page (figures inline as PNG) with the tuned gains, the
// comparison table, the figures, the run metadata and the job, for a design review. Private to
// tuner/report. With a front (a run with two or more soft goals), its section follows the gains.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "ftc/tune/job/job.hpp"
#include "report/figures.hpp"
#include "report/front_figures.hpp"

namespace ftc::tune::report_detail {

std::string report_html(const std::filesystem::path& run_dir, const Job& job,
                        const std::string& job_text, const nlohmann::json& gains,
                        const nlohmann::json& comparison, const nlohmann::json& run,
                        const std::vector<Figure>& figures, const Front* front = nullptr,
                        const std::vector<Figure>& front_figures = {});

}  // namespace ftc::tune::report_detail
