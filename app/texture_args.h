#pragma once
// The projective-texturing options that `confluent render` and `confluent evaluate` share.

#include <string>
#include <vector>

#include "app/command_line.h"
#include "render/projective_texture.h"

namespace confluent::app {

// --best-k K, --feather PX, --colour-balance.
std::vector<OptionSpec> TextureOptionSpecs();

// The options given (defaults otherwise). Throws UsageError for out-of-range values.
ProjectiveTextureOptions TextureOptionsFromArgs(const ParsedArgs& args);

}  // namespace confluent::app
