#pragma once
// What the process needs to open a loadable module that takes ftctune's symbols from it (the
// pagmo2 adapter, plant plugins): the modules are linked against nothing of ftctune's and find
// its functions in the program that opens them.
#include <filesystem>

namespace ftc::sim {

// The file this code was linked into: the ftctune executable, a test program, or the Python
// module (where /proc/self/exe would be the interpreter). Empty when it cannot be told.
std::filesystem::path this_image();

// Makes this image's symbols visible to the modules it opens. An executable exports them already
// (--export-dynamic); a shared object opened with RTLD_LOCAL, as Python opens its extension
// modules, keeps them to itself until it is reopened as global (it then stays as long as the
// process). Once per process; cheap after the first call.
void share_symbols_with_modules();

}  // namespace ftc::sim
