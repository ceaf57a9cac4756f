// SPDX-License-Identifier: MIT
#include "run/plots.h"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>
#include <vector>

namespace cpstep::run {

namespace fs = std::filesystem;

std::string find_gnuplot() {
  const char* path = std::getenv("PATH");
  if (!path) return "";
  std::stringstream dirs(path);
  for (std::string d; std::getline(dirs, d, ':');) {
    if (d.empty()) continue;
    const fs::path p = fs::path(d) / "gnuplot";
    if (::access(p.c_str(), X_OK) == 0 && fs::is_regular_file(p)) return p.string();
  }
  return "";
}

namespace {

// Runs a program in `cwd` with stdout and stderr appended to `log`; its exit
// status, or -1 when it could not be started.
int run_program(const std::vector<std::string>& args, const fs::path& cwd, const fs::path& log) {
  const pid_t pid = ::fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (fd >= 0) {
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      ::close(fd);
    }
    if (::chdir(cwd.c_str()) != 0) ::_exit(127);
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return -1;
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// A gnuplot string literal in single quotes (which it doubles inside).
std::string quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

// Columns of kinematics.dat.
constexpr int kTime = 1;
int axis_column(int axis, int order) { return 2 + 3 * axis + order; }  // order 0 v, 1 a, 2 j
constexpr int kPath = 2 + 3 * plan::kAxes;                            // measured v, a, j
constexpr int kPlan = kPath + 3;                                       // planned v, a, j

const char* const kAxisColours[plan::kAxes] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd"};

}  // namespace

std::string write_plots(const fs::path& dir, const CardJob& job, const RunMeter& meter,
                        const RunMeasure& m) {
  if (m.moves == 0) return "the card made no move event: nothing to plot";
  const std::string gnuplot = find_gnuplot();
  if (gnuplot.empty())
    return "gnuplot is not on PATH (install it, e.g. `apt-get install gnuplot-nox` or scripts/deps)";
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return fmt::format("cannot create {}: {}", dir.string(), ec.message());

  // Data: the card's path, the planned segment ends, the kinematics.
  {
    std::ofstream out(dir / "path_card.dat");
    out << fmt::format("# x_mm y_mm z_mm a_mm before the first move event and after every {}, and the last, "
                       "from the STEP/DIR pins\n",
                       meter.path_stride() == 1 ? std::string("one") : fmt::format("{}th", meter.path_stride()));
    for (const auto& p : meter.path()) out << fmt::format("{:.6f} {:.6f} {:.6f} {:.6f}\n", p[0], p[1], p[2], p[3]);
    std::ofstream plan(dir / "path_plan.dat");
    plan << "# x_mm y_mm z_mm a_mm at the planned step segments' ends\n";
    bool first = true;
    const auto add = [&](const plan::StepSegment& s) {
      for (const auto* p : first ? std::vector{&s.start, &s.end} : std::vector{&s.end}) {
        plan::PerAxis<double> mm{};
        for (int a = 0; a < plan::kAxes; ++a)
          if (job.machine.axes[a].present) mm[a] = double((*p)[a]) / job.machine.axes[a].steps_per_mm;
        plan << fmt::format("{:.6f} {:.6f} {:.6f} {:.6f}\n", mm[0], mm[1], mm[2], mm[3]);
      }
      first = false;
    };
    if (job.streamed) {  // the plan made again, step segment by step segment
      PlanCursor cursor(job);
      try {
        for (plan::StreamedStep st; cursor.next_step(st);) add(st.segment);
      } catch (const JobFileChanged& e) {
        plan << "# the planned path ends here: " << e.what() << "\n";
      }
    } else {
      for (const plan::StepSegment& s : job.planned.step_segments) add(s);
    }
    if (!out || !plan) return fmt::format("cannot write the path data in {}", dir.string());
  }
  const KinematicSeries ks = meter.series();
  {
    std::ofstream out(dir / "kinematics.dat");
    out << "# t_s";
    for (int a = 0; a < plan::kAxes; ++a)
      out << fmt::format(" v_{0} a_{0} j_{0}", plan::kAxisLetters[a]);
    out << " v_path a_path j_path v_plan a_plan j_plan\n";
    out << fmt::format("# measured from the STEP edges with central differences over h = {:.4f} s "
                       "(v), {:.4f} s (a), {:.4f} s (j)\n",
                       ks.window.v, ks.window.a, ks.window.j);
    for (size_t i = 0; i < ks.t.size(); ++i) {
      out << fmt::format("{:.6f}", ks.t[i]);
      for (int a = 0; a < plan::kAxes; ++a) {
        if (ks.v[a].empty()) out << " 0 0 0";
        else out << fmt::format(" {:.6g} {:.6g} {:.6g}", ks.v[a][i], ks.a[a][i], ks.j[a][i]);
      }
      out << fmt::format(" {:.6g} {:.6g} {:.6g} {:.6g} {:.6g} {:.6g}\n", ks.path_v[i], ks.path_a[i],
                         ks.path_j[i], ks.plan_v[i], ks.plan_a[i], ks.plan_j[i]);
    }
    if (!out) return fmt::format("cannot write {}", (dir / "kinematics.dat").string());
  }

  // The script. Axes that never stepped are left out of the plots.
  std::vector<int> moving;
  for (int a = 0; a < plan::kAxes; ++a)
    if (m.axes[a].present && m.axes[a].pulses > 0) moving.push_back(a);
  const std::string name = fs::path(job.job_file).filename().string();
  fs::remove(dir / "gnuplot.log", ec);
  const int terminal_ok = run_program({gnuplot, "-e", "set terminal pngcairo"}, dir, dir / "gnuplot.log");
  const std::string terminal = terminal_ok == 0 ? "pngcairo size 1200,800 font ',11'" : "png size 1200,800";
  std::ostringstream gp;
  gp << "# Written by cpstep run --plots; redraw with: gnuplot plots.gp\n";
  gp << "set terminal " << terminal << "\nset encoding utf8\nset termoption noenhanced\n";
  gp << "set grid\nset key above horizontal\n";
  gp << "set output 'path.png'\nset title " << quoted("XY path of " + name + ": card (from its STEP/DIR pins) over the plan") << "\n";
  gp << "set xlabel 'x (mm)'\nset ylabel 'y (mm)'\nset size ratio -1\n";
  gp << "set offsets graph 0.04, graph 0.04, graph 0.04, graph 0.04\n";
  gp << "plot 'path_plan.dat' using 1:2 with lines lw 5 lc rgb '#c8c8c8' title 'plan (step segment ends)', \\\n"
        "     'path_card.dat' using 1:2 with lines lw 1 lc rgb '#1f77b4' title 'card (pulses)'\n";
  gp << "set size noratio\nset offsets 0, 0, graph 0.05, graph 0.05\nset xlabel 'time from START (s)'\n";

  struct Quantity {
    const char* file;
    const char* what;
    const char* unit;
    int order;
    double plan::AxisConfig::*limit;
    double window;
  };
  const Quantity quantities[] = {
      {"speed.png", "velocity", "mm/s", 0, &plan::AxisConfig::max_velocity, ks.window.v},
      {"accel.png", "acceleration", "mm/s^2", 1, &plan::AxisConfig::max_accel, ks.window.a},
      {"jerk.png", "jerk", "mm/s^3", 2, &plan::AxisConfig::max_jerk, ks.window.j},
  };
  for (const Quantity& q : quantities) {
    gp << "set output '" << q.file << "'\n";
    gp << "set title " << quoted(fmt::format("{} of {}: measured from the card's STEP edges (h = {:.0f} ms), planned along the path",
                                             q.what, name, q.window * 1e3))
       << "\n";
    gp << "set ylabel '" << q.unit << "'\n";
    std::vector<std::string> curves;
    for (int a : moving)
      curves.push_back(fmt::format("'kinematics.dat' using {}:{} with lines lw 1 lc rgb '{}' title '{}'", kTime,
                                   axis_column(a, q.order), kAxisColours[a], plan::kAxisLetters[a]));
    curves.push_back(fmt::format("'kinematics.dat' using {}:{} with lines lw 2 lc rgb '#000000' title 'path (measured)'",
                                 kTime, kPath + q.order));
    curves.push_back(fmt::format("'kinematics.dat' using {}:{} with lines lw 1.5 dt 2 lc rgb '#ff7f0e' title 'path (plan)'",
                                 kTime, kPlan + q.order));
    // One pair of limit lines per distinct limit.
    std::set<double> limits;
    for (int a : moving) limits.insert(job.machine.axes[a].*q.limit);
    for (double l : limits) {
      std::string who;
      for (int a : moving)
        if (job.machine.axes[a].*q.limit == l) who += plan::kAxisLetters[a];
      curves.push_back(fmt::format("{:g} with lines dt 3 lc rgb '#808080' title 'limit {}'", l, who));
      curves.push_back(fmt::format("{:g} with lines dt 3 lc rgb '#808080' notitle", -l));
    }
    gp << "plot ";
    for (size_t i = 0; i < curves.size(); ++i) gp << (i ? ", \\\n     " : "") << curves[i];
    gp << "\n";
  }
  {
    std::ofstream out(dir / "plots.gp");
    out << gp.str();
    if (!out) return fmt::format("cannot write {}", (dir / "plots.gp").string());
  }
  for (const char* png : {"path.png", "speed.png", "accel.png", "jerk.png"}) fs::remove(dir / png, ec);
  const int rc = run_program({gnuplot, "plots.gp"}, dir, dir / "gnuplot.log");
  if (rc != 0)
    return fmt::format("gnuplot failed (exit {}); see {}", rc, (dir / "gnuplot.log").string());
  return "";
}

}  // namespace cpstep::run
