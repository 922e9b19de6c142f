// `sportsim course list|show`: the server's golf courses (ListCourses, GetCourse).
#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "absl/flags/declare.h"
#include "absl/flags/flag.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/cli.h"
#include "client/course_svg.h"
#include "sportsim/v1/swing.grpc.pb.h"

ABSL_DECLARE_FLAG(std::string, svg);
ABSL_DECLARE_FLAG(std::optional<int>, hole);

namespace sportsim::cli {
namespace {

constexpr double kMetresPerYard = 0.9144;

void PrintCourseLine(const v1::CourseInfo& c) {
  int par = 0;
  double length = 0;
  std::string pars;
  for (const v1::CourseHoleInfo& h : c.holes()) {
    par += static_cast<int>(h.par());
    length += h.length_m();
    absl::StrAppend(&pars, pars.empty() ? "" : " ", h.par());
  }
  std::printf("%-16s %2d holes, par %d (%s), %.0f m (%.0f yd)  %s\n", c.name().c_str(),
              c.holes_size(), par, pars.c_str(), length, length / kMetresPerYard,
              c.description().c_str());
}

int RunList(const Context& ctx, const std::vector<std::string>& args) {
  if (!args.empty()) return UsageError("course list takes no arguments, got '" + args[0] + "'");
  auto stub = v1::Swing::NewStub(ctx.channel);
  v1::ListCoursesResponse response;
  const grpc::Status status =
      stub->ListCourses(ctx.NewCall().get(), v1::ListCoursesRequest(), &response);
  if (!status.ok()) return ReportRpcError(status);
  if (ctx.format == Format::kJson) {
    std::cout << ToJson(response, false) << "\n";
    return 0;
  }
  for (const v1::CourseInfo& c : response.courses()) PrintCourseLine(c);
  return 0;
}

void PrintCourse(const v1::CourseInfo& c) {
  PrintCourseLine(c);
  std::printf("ground from %.1f m to %.1f m; wind %.1f m/s toward %.0f deg\n", c.min_z_m(),
              c.max_z_m(), c.wind_speed_mps(), c.wind_toward_deg());
  for (const v1::CourseHoleInfo& h : c.holes()) {
    std::printf("hole %u: par %u, stroke index %u, %.0f m (%.0f yd) from the %s tee; pin at "
                "(%.1f, %.1f, %.2f) m; green Stimp %.1f ft; %s\n",
                h.number(), h.par(), h.stroke_index(), h.length_m(),
                h.length_m() / kMetresPerYard, h.tees(0).name().c_str(), h.pin().x_m(),
                h.pin().y_m(), h.pin().z_m(), h.green_stimp_ft(), h.fairway().c_str());
    for (const v1::CourseTee& t : h.tees()) {
      std::printf("  tee %-8s (%.1f, %.1f, %.2f) m\n", t.name().c_str(), t.x_m(), t.y_m(),
                  t.z_m());
    }
  }
  std::printf("surfaces: %-10s %11s %9s %9s %9s %9s %7s\n", "", "restitution", "crit.angle",
              "bounce mu", "skid mu", "rolling", "Stimp");
  for (const v1::SurfaceInfo& s : c.surfaces()) {
    std::printf("  %-18s %11.3g %9.3g %9.3g %9.3g %9.4g %7.1f\n", s.name().c_str(),
                s.restitution_scale(), s.critical_angle_scale(), s.bounce_friction(),
                s.sliding_friction(), s.rolling_resistance(), s.stimp_ft());
  }
}

int RunShow(const Context& ctx, const std::vector<std::string>& args) {
  if (args.size() != 1) return UsageError("course show takes one course name (course list)");
  const std::optional<int> hole = absl::GetFlag(FLAGS_hole);
  if (hole && (*hole < 1 || *hole > 36)) {
    return UsageError(InvalidValue(absl::StrFormat("--hole: must be in [1, 36], got %d", *hole)));
  }
  const std::string svg = absl::GetFlag(FLAGS_svg);
  v1::GetCourseRequest request;
  request.set_name(args[0]);
  request.set_hole(static_cast<uint32_t>(hole.value_or(0)));
  auto stub = v1::Swing::NewStub(ctx.channel);
  v1::CourseInfo course;
  grpc::Status status = stub->GetCourse(ctx.NewCall().get(), request, &course);
  if (!status.ok()) return ReportRpcError(status);
  if (!svg.empty()) {
    // The drawing needs the geometry and every hole's tees and pins.
    v1::GetCourseRequest full;
    full.set_name(args[0]);
    full.set_geometry(true);
    v1::CourseInfo drawn;
    status = stub->GetCourse(ctx.NewCall().get(), full, &drawn);
    if (!status.ok()) return ReportRpcError(status);
    std::ofstream out(svg);
    out << CourseSvg(drawn, hole.value_or(0), nullptr);
    if (!out) return UsageError("cannot write --svg file '" + svg + "'");
  }
  if (ctx.format == Format::kJson) {
    std::cout << ToJson(course, false) << "\n";
    return 0;
  }
  PrintCourse(course);
  return 0;
}

}  // namespace

int RunCourse(const Context& ctx, const std::vector<std::string>& args) {
  if (args.empty()) return UsageError("course needs a subcommand: list or show");
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  if (args[0] == "list") return RunList(ctx, rest);
  if (args[0] == "show") return RunShow(ctx, rest);
  return UsageError("unknown course subcommand '" + args[0] + "' (list, show)");
}

}  // namespace sportsim::cli
