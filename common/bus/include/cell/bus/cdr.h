// XCDR1 encoding of the generated topic types (Fast CDR is a codec, not a DDS stack).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <fastcdr/exceptions/Exception.h>

#include "cell/bus/backend.h"
#include "cell/idl/meta.h"

namespace cell::bus {

template <class T>
std::vector<uint8_t> ToCdr(const T& v) {
  size_t cap = 4 + T::getCdrSerializedSize(v, 0) + 8;
  std::vector<uint8_t> buf(cap, 0);  // zeroed: Fast CDR skips alignment gaps without writing them
  eprosima::fastcdr::FastBuffer fb(reinterpret_cast<char*>(buf.data()), cap);
  eprosima::fastcdr::Cdr ser(fb, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR);
  ser.serialize_encapsulation();
  v.serialize(ser);
  buf.resize(ser.getSerializedDataLength());
  return buf;
}

// False on anything that is not a well-formed XCDR1 sample of T.
template <class T>
bool FromCdr(const uint8_t* data, size_t n, T& out) {
  if (n < 4 || data[0] != 0 || data[1] > 1) return false;  // CDR_BE / CDR_LE only (XCDR1)
  try {
    eprosima::fastcdr::FastBuffer fb(reinterpret_cast<char*>(const_cast<uint8_t*>(data)), n);
    eprosima::fastcdr::Cdr des(fb, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR);
    des.read_encapsulation();
    out.deserialize(des);
    return true;
  } catch (const eprosima::fastcdr::exception::Exception&) {
    return false;
  } catch (const std::exception&) {
    return false;
  }
}

template <class T>
std::vector<uint8_t> KeyCdr(const T& v) {
  if constexpr (!cell::idl::TypeMeta<T>::kKeyed) {
    return {};
  } else {
    size_t cap = T::getKeyMaxCdrSerializedSize(0) + 8;
    std::vector<uint8_t> buf(cap, 0);
    eprosima::fastcdr::FastBuffer fb(reinterpret_cast<char*>(buf.data()), cap);
    eprosima::fastcdr::Cdr ser(fb, eprosima::fastcdr::Cdr::BIG_ENDIANNESS);
    v.serializeKey(ser);
    buf.resize(ser.getSerializedDataLength());
    return buf;
  }
}

template <class T>
const TypeSupport& TypeSupportFor() {
  static const TypeSupport ts = [] {
    TypeSupport t;
    t.name = cell::idl::TypeMeta<T>::kName;
    t.keyed = cell::idl::TypeMeta<T>::kKeyed;
    t.max_size = 4 + T::getMaxCdrSerializedSize(0);
    t.key_max_size = T::getKeyMaxCdrSerializedSize(0);
    t.key_from_cdr = [](const uint8_t* d, size_t n, std::vector<uint8_t>& key) {
      T v;
      if (!FromCdr(d, n, v)) return false;
      key = KeyCdr(v);
      return true;
    };
    return t;
  }();
  return ts;
}

}  // namespace cell::bus
