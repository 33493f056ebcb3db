// SPDX-License-Identifier: BSD-3-Clause
// Names of DdsError values and the mapping from Cyclone return codes.
#include "src/dds/dds_error.hpp"

#include <dds/dds.h>

namespace raymap::dds {

const char* toString(DdsError error) noexcept {
  switch (error) {
    case DdsError::kError:
      return "error";
    case DdsError::kBadParameter:
      return "bad_parameter";
    case DdsError::kPreconditionNotMet:
      return "precondition_not_met";
    case DdsError::kOutOfResources:
      return "out_of_resources";
    case DdsError::kAlreadyDeleted:
      return "already_deleted";
    case DdsError::kTimeout:
      return "timeout";
    case DdsError::kIllegalOperation:
      return "illegal_operation";
    case DdsError::kUnsupported:
      return "unsupported";
  }
  return "unknown";
}

DdsError ddsErrorFromReturnCode(std::int32_t return_code) noexcept {
  switch (return_code) {
    case DDS_RETCODE_BAD_PARAMETER:
      return DdsError::kBadParameter;
    case DDS_RETCODE_PRECONDITION_NOT_MET:
      return DdsError::kPreconditionNotMet;
    case DDS_RETCODE_OUT_OF_RESOURCES:
      return DdsError::kOutOfResources;
    case DDS_RETCODE_ALREADY_DELETED:
      return DdsError::kAlreadyDeleted;
    case DDS_RETCODE_TIMEOUT:
      return DdsError::kTimeout;
    case DDS_RETCODE_ILLEGAL_OPERATION:
      return DdsError::kIllegalOperation;
    case DDS_RETCODE_UNSUPPORTED:
      return DdsError::kUnsupported;
    default:
      return DdsError::kError;
  }
}

}  // namespace raymap::dds
