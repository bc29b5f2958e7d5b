// `semap query OUT --class cup --on table` / `--near chair --within 1.0`: objects of a run's
// scene graph (OUT/scene_graph.json, issue 39) as JSON lines, one object per line.
#include <cstdio>

#include "apps/semap/commands.hpp"
#include "semap/core/labels.hpp"
#include "semap/navigation/scene_graph.hpp"

namespace semap::app {

namespace {
/// Issue 44 (third round), class 8: a misspelt class matched nothing and exited 0 silently.
const CLI::Validator kKnownClass(
    [](const std::string& name) {
      return class_from_name(name) ? std::string() : "'" + name + "' is not a class name";
    },
    "CLASS");
}  // namespace

void add_query_command(CLI::App& app, CommandRunner& run) {
  auto* cmd = app.add_subcommand("query", "Objects of a run's scene graph by class and relation, as JSON lines");
  struct Args {
    std::string out;
    SceneQuery query;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("out", args->out, "output folder of `semap run` (or its scene_graph.json)")->required();
  cmd->add_option("--class", args->query.class_name, "class of the objects listed (default: every class)")->check(kKnownClass);
  cmd->add_option("--on", args->query.on, "only objects on an object of this class (or 'floor', or a node id)");
  cmd->add_option("--in", args->query.in, "only objects in an object of this class (or a node id)");
  cmd->add_option("--near", args->query.near, "only objects near an object of this class")->check(kKnownClass);
  cmd->add_option("--within", args->query.within_m, "--near distance between centroids, m (default: the graph's near_distance_m)")
      ->check(finite_in(0.0, 1e6));
  cmd->callback([&run, args] {
    run = [args]() -> int {
      const SceneGraph graph = load_scene_graph(args->out);
      query_scene_graph(graph, args->query, [](const nlohmann::json& j) { std::printf("%s\n", j.dump().c_str()); });
      return 0;
    };
  });
}

}  // namespace semap::app
