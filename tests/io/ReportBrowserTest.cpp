// report.html in a real browser: headless Chromium (Debian's `chromium`) opens the report of a
// synthetic run, and of a synthetic study, with a checking script added at its end. The script measures every SVG and
// image as laid out (non-zero size), draws each SVG onto a canvas and counts its inked pixels
// (and the colours of the pressure-mat and block-map pictures), and lists the resources the page fetched
// over http(s); it writes the counts into the DOM, which --dump-dom prints. The same script on
// a page with a zero-size SVG, a blank SVG and a broken image must report all three, so the
// check can fail. Name resolution is disabled, so the page must work offline.
//
// Chromium missing is a failure, not a skip: install it with `apt-get install chromium`
// (scripts/setup --tests does).
#include <gtest/gtest.h>
#include <io/ArrayReport.h>
#include <io/StudyReport.h>

#include <cstdlib>
#include <map>
#include <regex>
#include <sstream>

#include "SyntheticArrayRun.h"
#include "SyntheticStudy.h"

namespace fs = std::filesystem;

namespace {

const char* kCheckScript = R"(<script>
(function () {
  var svgs = Array.prototype.filter.call(document.querySelectorAll('svg'),
      function (s) { return !s.parentElement.closest('svg'); });
  var imgs = Array.prototype.slice.call(document.images);
  var zero = 0, broken = 0, blank = 0, drawn = 0, matColours = 1e9, mapColours = 1e9;
  var mats = document.querySelectorAll('svg.mat').length;
  var maps = document.querySelectorAll('svg.map').length;
  svgs.concat(imgs).forEach(function (e) {
    var r = e.getBoundingClientRect();
    if (!(r.width > 0 && r.height > 0)) zero++;
  });
  imgs.forEach(function (i) { if (!(i.complete && i.naturalWidth > 0)) broken++; });
  var http = performance.getEntriesByType('resource').filter(function (e) {
    return /^(https?|ftp|wss?):/.test(e.name); }).length;
  var pending = svgs.length;
  function finish() {
    var out = document.createElement('pre');
    out.textContent = 'BAGSIM-' + 'CHECK svgs=' + svgs.length + ' imgs=' + imgs.length + ' zero=' + zero +
      ' broken=' + broken + ' blank=' + blank + ' drawn=' + drawn + ' mats=' + mats +
      ' matcolours=' + (mats ? matColours : 0) + ' maps=' + maps +
      ' mapcolours=' + (maps ? mapColours : 0) + ' http=' + http + ' END';
    document.body.appendChild(out);
  }
  if (!pending) finish();
  svgs.forEach(function (s) {
    var r = s.getBoundingClientRect();
    var w = Math.max(1, Math.round(r.width)), h = Math.max(1, Math.round(r.height));
    var img = new Image();
    img.onload = function () {
      var c = document.createElement('canvas');
      c.width = w; c.height = h;
      var g = c.getContext('2d');
      g.fillStyle = '#fff'; g.fillRect(0, 0, w, h);
      g.drawImage(img, 0, 0, w, h);
      var d = g.getImageData(0, 0, w, h).data, ink = 0, colours = {};
      for (var k = 0; k < d.length; k += 4) {
        if (d[k] < 235 || d[k + 1] < 235 || d[k + 2] < 235) ink++;
        colours[(d[k] >> 4) * 256 + (d[k + 1] >> 4) * 16 + (d[k + 2] >> 4)] = 1;
      }
      if (r.width > 0 && r.height > 0 && ink >= 0.005 * w * h) drawn++; else blank++;
      if (s.classList.contains('mat')) matColours = Math.min(matColours, Object.keys(colours).length);
      if (s.classList.contains('map')) mapColours = Math.min(mapColours, Object.keys(colours).length);
      if (--pending === 0) finish();
    };
    img.onerror = function () { broken++; if (--pending === 0) finish(); };
    img.src = 'data:image/svg+xml;charset=utf-8,' +
        encodeURIComponent(new XMLSerializer().serializeToString(s));
  });
})();
</script>)";

std::string readFile(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

/// The browser: $BAGSIM_CHROMIUM, else chromium or chromium-browser on the PATH ("" if none).
std::string findChromium() {
    if (const char* env = std::getenv("BAGSIM_CHROMIUM")) return env;
    for (const char* name : {"chromium", "chromium-browser"}) {
        const std::string cmd = std::string("command -v ") + name + " > /dev/null 2>&1";
        if (std::system(cmd.c_str()) == 0) return name;
    }
    return "";
}

/// Opens `page` with the check script added before </body>; returns the counts it wrote.
std::map<std::string, int> checkInChromium(const std::string& chromium, const fs::path& page) {
    std::string html = readFile(page);
    const size_t end = html.rfind("</body>");
    html.insert(end == std::string::npos ? html.size() : end, kCheckScript);
    const fs::path checked = page.parent_path() / (page.stem().string() + "-checked.html");
    std::ofstream(checked) << html;
    const fs::path profile = page.parent_path() / "chromium-profile";
    const fs::path dom = page.parent_path() / (page.stem().string() + "-dom.txt");
    const std::string cmd = "timeout 60 " + chromium +
                            " --headless --no-sandbox --disable-gpu --no-first-run"
                            " --disable-extensions --host-resolver-rules='MAP * ~NOTFOUND'"
                            " --virtual-time-budget=10000 --user-data-dir='" +
                            profile.string() + "' --dump-dom 'file://" +
                            fs::absolute(checked).string() + "' > '" + dom.string() + "' 2> '" +
                            dom.string() + ".err'";
    const int rc = std::system(cmd.c_str());
    EXPECT_EQ(rc, 0) << cmd << "\n" << readFile(dom.string() + ".err");
    const std::string out = readFile(dom);
    std::smatch m;
    std::map<std::string, int> counts;
    if (!std::regex_search(out, m, std::regex("BAGSIM-CHECK ([^<]*) END"))) {
        ADD_FAILURE() << "the check script wrote nothing into the page (" << page.string() << ")";
        return counts;
    }
    std::istringstream s(m[1].str());
    for (std::string kv; s >> kv;) {
        const size_t eq = kv.find('=');
        counts[kv.substr(0, eq)] = std::stoi(kv.substr(eq + 1));
    }
    return counts;
}

int count(const std::string& s, const std::string& what) {
    int n = 0;
    for (size_t i = s.find(what); i != std::string::npos; i = s.find(what, i + 1)) ++n;
    return n;
}

}  // namespace

TEST(ReportBrowser, ChromiumRendersEveryImageOfTheReportOffline) {
    const std::string chromium = findChromium();
    ASSERT_FALSE(chromium.empty())
        << "Chromium is not installed, and this test opens report.html in a real browser. "
           "Install it with `sudo apt-get install chromium` (Debian; scripts/setup --tests "
           "installs it), or set BAGSIM_CHROMIUM to a Chromium or Chrome binary.";
    const fs::path dir = fs::path(BAGSIM_BINARY_DIR) / "test-output" / "io" / "report-browser";
    fs::create_directories(dir.parent_path());
    io::test::writeSyntheticRun(dir, true);
    io::writeArrayReport(dir, dir / "report.html");
    const std::string html = readFile(dir / "report.html");
    const int svgs = count(html, "<svg ");
    ASSERT_GT(svgs, 10);

    std::map<std::string, int> c = checkInChromium(chromium, dir / "report.html");
    EXPECT_EQ(c["svgs"], svgs);
    EXPECT_EQ(c["zero"], 0) << "SVGs or images laid out at zero size";
    EXPECT_EQ(c["broken"], 0) << "images that did not load";
    EXPECT_EQ(c["blank"], 0) << "SVGs that drew (next to) nothing";
    EXPECT_EQ(c["drawn"], svgs);
    EXPECT_EQ(c["mats"], 4);
    EXPECT_GE(c["matcolours"], 8) << "a pressure-mat picture shows fewer than 8 colours";
    EXPECT_EQ(c["http"], 0) << "the page fetched something over the network";

    // The check fails on what it must catch: a zero-size SVG, a blank one, a broken image.
    const fs::path bad = dir / "broken.html";
    std::ofstream(bad) << "<!DOCTYPE html><html><body>"
                          "<svg xmlns='http://www.w3.org/2000/svg' width='0' height='0'></svg>"
                          "<svg xmlns='http://www.w3.org/2000/svg' width='200' height='100'>"
                          "<rect width='200' height='100' fill='#fff'/></svg>"
                          "<img src='data:image/png;base64,iVBORw0KGgo=' width='20' height='20'>"
                          "</body></html>";
    c = checkInChromium(chromium, bad);
    EXPECT_EQ(c["svgs"], 2);
    EXPECT_EQ(c["zero"], 1);
    EXPECT_EQ(c["blank"], 2);
    EXPECT_EQ(c["broken"], 1);
    EXPECT_EQ(c["drawn"], 0);
}

TEST(ReportBrowser, ChromiumRendersEveryImageOfAStudyReportOffline) {
    const std::string chromium = findChromium();
    ASSERT_FALSE(chromium.empty())
        << "Chromium is not installed, and this test opens report.html in a real browser. "
           "Install it with `sudo apt-get install chromium` (Debian; scripts/setup --tests "
           "installs it), or set BAGSIM_CHROMIUM to a Chromium or Chrome binary.";
    const fs::path dir =
        fs::path(BAGSIM_BINARY_DIR) / "test-output" / "io" / "report-browser-study";
    fs::create_directories(dir.parent_path());
    io::test::writeSyntheticMapStudy(dir, true);
    io::writeStudyReport(dir, dir / "report.html");
    const std::string html = readFile(dir / "report.html");
    const int svgs = count(html, "<svg ");
    ASSERT_GE(svgs, 15);

    const std::map<std::string, int> c = checkInChromium(chromium, dir / "report.html");
    EXPECT_EQ(c.at("svgs"), svgs);
    EXPECT_EQ(c.at("zero"), 0) << "SVGs or images laid out at zero size";
    EXPECT_EQ(c.at("broken"), 0) << "images that did not load";
    EXPECT_EQ(c.at("blank"), 0) << "SVGs that drew (next to) nothing";
    EXPECT_EQ(c.at("drawn"), svgs);
    EXPECT_EQ(c.at("mats"), 0);
    EXPECT_EQ(c.at("maps"), 6);
    // Two values (middle and edge column), grey cells, white borders, text: at least 4.
    EXPECT_GE(c.at("mapcolours"), 4) << "a block map shows fewer than 4 colours";
    EXPECT_EQ(c.at("http"), 0) << "the page fetched something over the network";
}
