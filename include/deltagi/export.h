// What libdeltagi.so exports. The library is compiled with hidden visibility (cmake/package.cmake), so that
// an application reaches only the API declared in include/deltagi/ and the library's inside (src/) can change
// without breaking it. Each public header declares its API between DELTAGI_API_BEGIN and DELTAGI_API_END,
// which export everything declared there: its functions, its classes' members and their type information
// (InputError is thrown across the library's boundary).
#pragma once

#define DELTAGI_API_BEGIN _Pragma("GCC visibility push(default)")
#define DELTAGI_API_END _Pragma("GCC visibility pop")
