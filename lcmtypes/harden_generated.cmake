# Run after lcm-gen --cpp (cmake -DHEADERS="a.hpp;b.hpp" -P harden_generated.cmake): makes the
# generated decoders refuse lengths that lcm-gen 1.3.1 trusts. A message comes from the network or
# a log file, and as generated
#   - a string length of 0 or below reaches std::string::assign(p, len - 1): std::length_error,
#     which escapes LCM's C dispatch and ends the process (one malformed packet ends furutad),
#     and INT32_MIN overflows `len - 1` (UB) and reads 2 GB past the buffer;
#   - a negative array count reaches std::vector::resize: std::length_error again; a count larger
#     than the bytes left (every element takes at least one) makes resize allocate up to 2 GB for a
#     60-byte packet before the decode fails;
#   - a string with a NUL inside, or without its terminating NUL, decodes to something the encoder
#     (which writes strlen() bytes) can never send back: a message would not survive a round trip.
# All become a decode error (-1), like any other malformed message. The build fails if the
# generated code no longer has the expected shape, so a new lcm-gen is looked at, not trusted.
foreach(header IN LISTS HEADERS)
  if(NOT header)
    continue()
  endif()
  file(READ "${header}" text)
  set(before "${text}")
  # A string's length counts its terminating NUL: it is at least 1.
  string(REGEX REPLACE "if\\(__([A-Za-z0-9_]+)_len__ > maxlen - pos\\) return -1;"
                       "if(__\\1_len__ < 1 || __\\1_len__ > maxlen - pos) return -1;" text "${text}")
  # The string's bytes: no NUL before the last, and the last one NUL.
  string(REGEX REPLACE
         "\n( *)this->([A-Za-z0-9_]+)\\.assign\\(\\(\\(const char\\*\\)buf\\) \\+ offset \\+ pos, __([A-Za-z0-9_]+)_len__ - 1\\);"
         "\n\\1if(memchr((const char*)buf + offset + pos, 0, __\\3_len__ - 1) != NULL ||\n\\1   ((const char*)buf)[offset + pos + __\\3_len__ - 1] != 0) return -1;\n\\1this->\\2.assign(((const char*)buf) + offset + pos, __\\3_len__ - 1);"
         text "${text}")
  string(REGEX REPLACE "\n( *)if\\(this->([A-Za-z0-9_]+)\\) {\n( *)this->([A-Za-z0-9_]+)\\.resize\\(this->"
                       "\n\\1if(this->\\2 < 0 || this->\\2 > maxlen - pos) return -1;\n\\1if(this->\\2) {\n\\3this->\\4.resize(this->"
                       text "${text}")
  string(FIND "${before}" "_len__ > maxlen - pos" has_string)
  string(FIND "${before}" ".resize(this->" has_array)
  string(FIND "${text}" "_len__ < 1 ||" hardened_string)
  string(FIND "${text}" " < 0 || this->" hardened_array)
  string(FIND "${text}" "if(memchr(" hardened_nul)
  if((has_string GREATER -1 AND (hardened_string EQUAL -1 OR hardened_nul EQUAL -1))
     OR (has_array GREATER -1 AND hardened_array EQUAL -1))
    message(FATAL_ERROR "harden_generated.cmake: unexpected lcm-gen output in ${header}")
  endif()
  file(WRITE "${header}" "${text}")
endforeach()
