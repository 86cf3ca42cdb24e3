/* For the Wine test run only (scripts/windows-dll.sh test), never shipped: Windows 10 and later
 * have bcryptprimitives.dll, whose ProcessPrng the Rust standard library calls for random bytes
 * (HashMap seeds), but Wine 8 (Debian 12) lacks that DLL, so no Rust DLL would load. This one
 * gives ProcessPrng from BCryptGenRandom with the system RNG, which Wine has. */
#include <windows.h>

#include <bcrypt.h>

/* Fills data[0..len) with random bytes; TRUE on success (ProcessPrng's contract). */
__declspec(dllexport) BOOL WINAPI ProcessPrng(PBYTE data, SIZE_T len) {
    while (len > 0) {
        ULONG chunk = len > 0x40000000 ? 0x40000000 : (ULONG)len;
        if (!BCRYPT_SUCCESS(BCryptGenRandom(NULL, data, chunk, BCRYPT_USE_SYSTEM_PREFERRED_RNG))) return FALSE;
        data += chunk;
        len -= chunk;
    }
    return TRUE;
}
