// SPDX-License-Identifier: BSD-3-Clause
// raymap::dds::DdsError: the real-time error code of DDS calls (write, take, wait).
#pragma once

#include <cstdint>

namespace raymap::dds {

/// What a DDS call on the real-time path reports (the Cyclone return code, folded).
enum class DdsError : std::uint8_t {
  kError,               ///< DDS_RETCODE_ERROR or a code not listed here
  kBadParameter,        ///< DDS_RETCODE_BAD_PARAMETER (a deleted or wrong entity handle)
  kPreconditionNotMet,  ///< DDS_RETCODE_PRECONDITION_NOT_MET
  kOutOfResources,      ///< DDS_RETCODE_OUT_OF_RESOURCES (resource limits, memory)
  kAlreadyDeleted,      ///< DDS_RETCODE_ALREADY_DELETED (the entity or its participant is gone)
  kTimeout,             ///< DDS_RETCODE_TIMEOUT (a reliable KEEP_ALL writer blocked too long)
  kIllegalOperation,    ///< DDS_RETCODE_ILLEGAL_OPERATION
  kUnsupported,         ///< DDS_RETCODE_UNSUPPORTED
};

/// @brief Short, stable name ("timeout", "out_of_resources", ...). @rt allocates: no.
const char* toString(DdsError error) noexcept;

/// @brief Folds a negative Cyclone return code (dds_return_t) into a DdsError. @rt allocates: no.
DdsError ddsErrorFromReturnCode(std::int32_t return_code) noexcept;

}  // namespace raymap::dds
