// See opencv_runtime.hpp.
#include "toposlam/platform/opencv_runtime.hpp"

#include <cstdlib>

namespace toposlam {

void keepOpenCvOffOpenCl() { ::setenv("OPENCV_OPENCL_RUNTIME", "disabled", /*overwrite=*/0); }

}  // namespace toposlam
