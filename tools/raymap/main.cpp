// SPDX-License-Identifier: BSD-3-Clause
// raymap: the command line for building, inspecting and exporting occupancy maps.
#include <cstdio>
#include <exception>

#include "raymap/version.hpp"
#include <CLI/CLI.hpp>

#include "tools/raymap/commands.hpp"

int main(int argc, char** argv) {
  using namespace raymap::cli;
  CLI::App app{"raymap: occupancy maps from lidar rays (see docs/cli.md)", "raymap"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("raymap ") + RAYMAP_VERSION_STRING);
  int exit_code = kExitOk;
  addPopulateCommand(app, &exit_code);
  addInfoCommand(app, &exit_code);
  addExportCommand(app, &exit_code);
  addHeightmapCommand(app, &exit_code);
  addBenchCommand(app, &exit_code);
  addDemoCommand(app, &exit_code);
  addSimulateCommand(app, &exit_code);
  addDevicesCommand(app, &exit_code);
  addTopicsCommand(app, &exit_code);
  addEchoCommand(app, &exit_code);
  addReplayCommand(app, &exit_code);
  addRecordCommand(app, &exit_code);
  addSecurityCommand(app, &exit_code);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "raymap: error: %s\nRun 'raymap --help' or 'raymap COMMAND --help'.\n",
                 e.what());
    return kExitUsage;
  } catch (const std::exception& e) {
    // Library code reports errors by value; this catches what the standard library throws
    // (allocation failure) so the user still gets a message.
    std::fprintf(stderr, "raymap: error: %s\n", e.what());
    return kExitFailure;
  }
  return exit_code;
}
