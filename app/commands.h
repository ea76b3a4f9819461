#pragma once
// Every subcommand of the confluent binary. Each Make*Command lives in its own cmd_*.cc file;
// main.cc lists them.

#include "app/command_line.h"

namespace confluent::app {

CommandSpec MakeDemoCommand();           // cmd_demo.cc
CommandSpec MakeCalibConvertCommand();   // cmd_calib.cc
CommandSpec MakeCalibCheckCommand();     // cmd_calib_check.cc
CommandSpec MakeCalibrateCommand();      // cmd_calibrate.cc
CommandSpec MakeCaptureInfoCommand();    // cmd_capture.cc
CommandSpec MakeMeshInfoCommand();       // cmd_mesh.cc
CommandSpec MakeRenderInfoCommand();     // cmd_render_info.cc
CommandSpec MakeSynthCommand();          // cmd_synth.cc
CommandSpec MakeSilhouettesCommand();    // cmd_silhouettes.cc
CommandSpec MakeAnimateCommand();        // cmd_animate.cc
CommandSpec MakeTrackCommand();          // cmd_track.cc
CommandSpec MakeCorrespondCommand();     // cmd_correspond.cc
CommandSpec MakeRunCommand();            // cmd_run.cc
CommandSpec MakeEvaluateCommand();       // cmd_evaluate.cc
CommandSpec MakeViewCommand();           // cmd_view.cc
CommandSpec MakeRenderCommand();         // cmd_render.cc
CommandSpec MakeExportCommand();         // cmd_export.cc

}  // namespace confluent::app
