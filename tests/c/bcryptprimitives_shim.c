/* Test-only stand-in for bcryptprimitives.dll, which Wine 8.0 lacks and Rust's
 * std (>= 1.78) imports for ProcessPrng: tests/python/test_platforms.py builds
 * it beside the harness it runs under wine. Never shipped in an FMU (a real
 * Windows has the system DLL). */
#include <windows.h>
#include <ntsecapi.h>

__declspec(dllexport) BOOL WINAPI ProcessPrng(PBYTE data, SIZE_T len) {
    while (len > 0) {
        ULONG n = len > 0x10000000 ? 0x10000000 : (ULONG)len;
        if (!RtlGenRandom(data, n)) return FALSE;
        data += n;
        len -= n;
    }
    return TRUE;
}
