// Loadable source modules: frame sources whose libraries are heavy to load (OpenCV's videoio and the
// ~100 shared libraries behind it) live in their own shared object, loaded the first time a URI needs
// them, so a program that never opens a video does not pay for them at start-up.
//
// A module `NAME` is the file `toposlam-source-NAME.so`, looked for in this order:
//   1. $TOPOSLAM_MODULE_DIR, when set (and then only there: an explicit choice, e.g. for a test);
//   2. next to the installed program: <program dir>/../LIBDIR/toposlam (the package's layout);
//   3. the build tree's module folder (programs run from the build tree).
// Loaded modules stay loaded for the life of the process. Private to platform/files.
// Thread-safety: any thread (one lock).
#pragma once

#include <string>

namespace toposlam {

/// The address of `symbol` in module `name`, loading the module on first use. Throws FrameSourceError
/// naming the module, every folder searched and the loader's own message when it cannot.
void* sourceModuleSymbol(const std::string& name, const std::string& symbol);

}  // namespace toposlam
