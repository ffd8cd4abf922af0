#include "ReportPage.h"

#include <io/InputError.h>
#include <io/StudyTable.h>

#include <cctype>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "SvgPlot.h"

namespace io::report {

namespace fs = std::filesystem;

int CsvTable::find(const std::string& name) const {
    for (size_t i = 0; i < header.size(); ++i)
        if (header[i] == name) return int(i);
    return -1;
}

double CsvTable::number(size_t row, int column) const {
    const std::string& cell = rows[row].at(size_t(column));
    char* end = nullptr;
    const double v = std::strtod(cell.c_str(), &end);
    if (cell.empty() || end != cell.c_str() + cell.size())
        throw InputError(path, lines[row], "",
                         "column " + std::to_string(column + 1) + " '" + header[size_t(column)] +
                             "': '" + cell + "' is not a number");
    return v;
}

std::string lower(std::string s) {
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

std::string join(const std::vector<std::string>& v, const char* sep) {
    std::string s;
    for (size_t i = 0; i < v.size(); ++i) s += (i ? sep : "") + v[i];
    return s;
}

std::string readWholeFile(const fs::path& p) {
    std::error_code ec;
    if (!fs::is_regular_file(p, ec)) throw InputError(p.string(), 0, "", "is not a regular file");
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    if (!in && !in.eof()) throw InputError(p.string(), 0, "", "cannot be read");
    return s.str();
}

std::string readTextIfPresent(const fs::path& p) {
    std::error_code ec;
    if (!fs::exists(p, ec)) return "";
    return readWholeFile(p);
}

CsvTable readCsvTable(const fs::path& file, const std::vector<std::string>& columns, bool optional,
                      const std::string& missingHelp) {
    CsvTable t;
    t.path = file.string();
    std::error_code ec;
    if (!fs::exists(file, ec)) {
        if (optional) return t;
        throw InputError(t.path, 0, "", "missing: " + missingHelp);
    }
    const std::string text = readWholeFile(file);
    t.present = true;
    std::istringstream in(text);
    std::string line;
    if (!std::getline(in, line))
        throw InputError(t.path, 1, "", "empty; expected the header " + join(columns));
    if (!line.empty() && line.back() == '\r') line.pop_back();
    t.header = splitCsvLine(line);
    for (const std::string& c : columns)
        if (t.find(c) < 0)
            throw InputError(t.path, 1, "",
                             "the header '" + line + "' has no column '" + c + "'; expected " +
                                 join(columns) + " (docs/output-layout.md)");
    const bool endsWithBreak = !text.empty() && text.back() == '\n';
    for (int n = 2; std::getline(in, line); ++n) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.empty()) continue;
        std::vector<std::string> cells = splitCsvLine(line);
        if (cells.size() != t.header.size()) {
            if (in.peek() == EOF && !endsWithBreak) break;  // cut short by a killed run
            throw InputError(t.path, n, "",
                             std::to_string(cells.size()) + " cells; the header has " +
                                 std::to_string(t.header.size()) + " (" + join(t.header) + ")");
        }
        t.rows.push_back(std::move(cells));
        t.lines.push_back(n);
    }
    return t;
}

const char* const kCss =
    "body{font-family:sans-serif;margin:1.5em auto;max-width:1250px;color:#222;line-height:1.4;"
    "padding:0 1em}h1{font-size:1.6em;margin-bottom:0.2em}h2{margin-top:1.6em;border-bottom:1px "
    "solid #ccc}table{border-collapse:collapse;margin:0.5em 0}td,th{border:1px solid #ccc;"
    "padding:3px 8px;text-align:left;vertical-align:top}th{background:#f0f0f0}td.n{text-align:"
    "right;font-variant-numeric:tabular-nums;white-space:nowrap}td.ok,td.warning,td.fail,td.na{"
    "white-space:nowrap}.banner{border:3px solid #b00;background:#fde8e8;"
    "padding:0.8em 1em;font-size:1.15em;margin:1em 0}.banner b{color:#b00}.ok{background:"
    "#dff0d8}.warning{background:#fcf0c8}.fail{background:#f6d0d0;font-weight:bold}.na{background:"
    "#eee;color:#555}.mats{display:flex;flex-wrap:wrap;gap:1.2em;align-items:flex-start}"
    "figure{margin:0}figcaption{font-size:0.92em;max-width:220px}.plots{display:flex;flex-wrap:"
    "wrap;gap:0.8em}svg{max-width:100%;height:auto}pre{background:#f6f6f6;padding:0.6em;"
    "overflow-x:auto;font-size:0.9em}details{margin:0.5em 0}summary{cursor:pointer;font-weight:"
    "bold}.muted{color:#666}";

std::string formatStatusCell(const std::string& status) {
    const std::string s = lower(status);
    if (s == "ok") return "<td class='ok'>&#10004; ok</td>";
    if (s == "warning" || s == "partial")
        return "<td class='warning'>&#9888; " + svg::escape(s) + "</td>";
    if (s == "fail" || s == "failed")
        return "<td class='fail'>&#10008; " + svg::escape(s) + "</td>";
    return "<td class='na'>" + svg::escape(status.empty() ? "n/a" : status) + "</td>";
}

std::string drawColourBar(const ColourBar& b) {
    using svg::num;
    const double h = b.height, top = 24, x = 8, w = 22;
    const double lo = b.lo, hi = b.hi > b.lo ? b.hi : b.lo + 1.0;
    const double total =
        h + top + 14 + 18.0 * double(b.swatches.size()) + (b.note.empty() ? 0.0 : 18.0);
    auto Y = [&](double v) { return top + h - (v - lo) / (hi - lo) * h; };
    std::ostringstream os;
    os << "<svg xmlns='http://www.w3.org/2000/svg' role='img' class='colourbar' width='120' "
          "height='"
       << total << "' viewBox='0 0 120 " << total
       << "' font-family='sans-serif' font-size='11'><title>" << svg::escape(b.title)
       << "</title><text x='0' y='14' font-weight='bold'>" << svg::escape(b.label) << "</text>";
    const int n = 60;
    for (int i = 0; i < n; ++i)
        os << "<rect x='" << x << "' y='" << num(top + h - (i + 1) * h / n, "%.1f") << "' width='"
           << w << "' height='" << num(h / n + 0.5, "%.1f") << "' fill='"
           << svg::getViridis((i + 0.5) / n) << "'/>";
    os << "<rect x='" << x << "' y='" << top << "' width='" << w << "' height='" << h
       << "' fill='none' stroke='#888'/>";
    const std::vector<double> ticks = svg::calcTicks(lo, hi, 6);
    const double step = ticks.size() > 1 ? ticks[1] - ticks[0] : 1.0;
    for (double v : ticks) {
        const double y = Y(v);
        os << "<line x1='" << x + w << "' x2='" << x + w + 5 << "' y1='" << num(y, "%.1f")
           << "' y2='" << num(y, "%.1f") << "' stroke='#333'/><text x='" << x + w + 8 << "' y='"
           << num(y + 4, "%.1f") << "'>" << (b.saturatedTop && v >= hi - 1e-9 ? "&#8805; " : "")
           << svg::formatTick(v, step) << "</text>";
    }
    if (std::isfinite(b.ref) && b.ref > lo && b.ref < hi) {
        const double y = Y(b.ref);
        os << "<line x1='" << x - 4 << "' x2='" << x + w + 4 << "' y1='" << num(y, "%.1f")
           << "' y2='" << num(y, "%.1f") << "' stroke='#000' stroke-width='2'/><text x='"
           << x + w + 8 << "' y='" << num(y + 4, "%.1f") << "' font-weight='bold'>"
           << svg::escape(b.refLabel) << "</text>";
    }
    double y = top + h + 14;
    for (const auto& [fill, text] : b.swatches) {
        os << "<rect x='" << x << "' y='" << y << "' width='" << w << "' height='12' fill='" << fill
           << "' stroke='#888'/><text x='" << x + w + 6 << "' y='" << y + 10 << "'>"
           << svg::escape(text) << "</text>";
        y += 18;
    }
    if (!b.note.empty())
        os << "<text x='0' y='" << y + 12 << "' font-size='10'>" << svg::escape(b.note)
           << "</text>";
    os << "</svg>";
    return os.str();
}

void writePageFile(const std::string& html, const fs::path& out) {
    const fs::path tmp = out.string() + ".tmp";
    {
        std::ofstream f(tmp, std::ios::trunc | std::ios::binary);
        f << html;
        if (!f.flush()) throw std::runtime_error("cannot write " + tmp.string());
    }
    std::error_code ec;
    fs::rename(tmp, out, ec);
    if (ec) {
        fs::remove(tmp, ec);
        throw std::runtime_error("cannot write " + out.string() + ": " + ec.message());
    }
}

}  // namespace io::report
