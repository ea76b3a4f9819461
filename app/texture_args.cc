#include "app/texture_args.h"

#include <cstdio>

#include "core/error.h"

namespace confluent::app {

std::vector<OptionSpec> TextureOptionSpecs() {
  return {
      {"best-k", "K", "cameras blended per pixel (default 3)"},
      {"feather", "PX", "feathering width near silhouette edges, pixels (default 8)"},
      {"colour-balance", "", "fit per-camera colour gains on overlaps"},
  };
}

ProjectiveTextureOptions TextureOptionsFromArgs(const ParsedArgs& args) {
  ProjectiveTextureOptions options;
  options.best_k = args.get_int("best-k", options.best_k);
  options.feather_px = args.get_double("feather", options.feather_px);
  options.colour_balance = args.has("colour-balance");
  options.Check();
  return options;
}

}  // namespace confluent::app
