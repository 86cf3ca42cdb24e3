/* Linked by lld-link (rustup's rust-lld in the MSVC linker's flavour, the stand-in here for
 * Microsoft's link.exe) against lib/sketchbody.lib, without any C runtime start-up code
 * (scripts/windows-dll.sh test): shows that an MSVC-style link takes the dlltool-made import
 * library, with the header's plain declarations (no __declspec(dllimport)). Exits 0 when the
 * DLL's version string equals the header's, else 1. */
#include <sketchbody.h>

__declspec(dllimport) void __stdcall ExitProcess(unsigned code);

/* The entry point (/entry:probe_main): compares the strings byte by byte. */
void probe_main(void) {
    const char *lib = skb_version(), *header = SKB_VERSION_STRING;
    unsigned i = 0;
    while (lib[i] != '\0' && lib[i] == header[i]) ++i;
    ExitProcess(lib[i] == header[i] ? 0 : 1);
}
