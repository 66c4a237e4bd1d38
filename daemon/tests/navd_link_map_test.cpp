// The vehicle binary's link map: navd (NAVD_PATH) contains no symbol of the survey simulator
// (nav::sim, hil-tests/sim) or of the report and its OpenCV figures (nav::report), read with
// `nm -C`. The same count on navtool (NAVTOOL_PATH), which links both, is the control that the
// patterns match demangled symbols at all. Skipped with the reason when nm is not installed.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <string>

namespace {

struct Symbols {
  int exit_code = -1;
  std::string text;  ///< `nm -C` output
};

Symbols demangled_symbols(const std::string& binary) {
  Symbols s;
  FILE* pipe = ::popen(("nm -C '" + binary + "' 2>&1").c_str(), "r");
  if (pipe == nullptr) return s;
  char buffer[65536];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0;)
    s.text.append(buffer, n);
  const int status = ::pclose(pipe);
  s.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return s;
}

/// Lines of `text` that name a symbol in `ns` ("nav::sim::"), with up to 3 of them in `examples`.
int count_lines_naming(const std::string& text, const std::string& ns, std::string* examples) {
  int count = 0;
  std::size_t begin = 0;
  while (begin < text.size()) {
    std::size_t end = text.find('\n', begin);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(begin, end - begin);
    if (line.find(ns) != std::string::npos) {
      if (++count <= 3) *examples += "  " + line + "\n";
    }
    begin = end + 1;
  }
  return count;
}

bool have_nm() { return std::system("command -v nm >/dev/null 2>&1") == 0; }

TEST(NavdLinkMap, NavdHasNoSimulatorOrReportSymbols) {
  if (!have_nm()) GTEST_SKIP() << "nm (binutils) not installed: cannot read navd's symbols";
  const Symbols navd = demangled_symbols(NAVD_PATH);
  ASSERT_EQ(navd.exit_code, 0) << "nm -C " << NAVD_PATH << ":\n" << navd.text.substr(0, 2000);
  ASSERT_GT(navd.text.size(), 1000u) << "nm found almost no symbols: stripped binary?";
  // navd's own service code is there: the patterns below would see the others.
  EXPECT_NE(navd.text.find("nav::daemon::service::"), std::string::npos);
  for (const char* ns : {"nav::sim::", "nav::report::", "nav::hil::"}) {
    std::string examples;
    EXPECT_EQ(count_lines_naming(navd.text, ns, &examples), 0)
        << "navd links " << ns << " code, e.g.:\n"
        << examples;
  }
}

TEST(NavdLinkMap, NavtoolControlHasBoth) {
  if (!have_nm()) GTEST_SKIP() << "nm (binutils) not installed: cannot read navtool's symbols";
  const Symbols navtool = demangled_symbols(NAVTOOL_PATH);
  ASSERT_EQ(navtool.exit_code, 0) << navtool.text.substr(0, 2000);
  std::string examples;
  EXPECT_GT(count_lines_naming(navtool.text, "nav::sim::", &examples), 0);
  EXPECT_GT(count_lines_naming(navtool.text, "nav::report::", &examples), 0);
}

}  // namespace
