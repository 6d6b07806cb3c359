#!/usr/bin/env python3
"""Checks what the layer libraries export (issue 19: symbols hidden by default).

Each library given must export GiPSi's API (symbols in namespace gipsi) and nothing of the
header-only libraries it uses inside: no instantiation of Eigen or nlohmann::json templates,
whose symbols would otherwise be interposed between a user's program (with its own Eigen or
JSON version) and GiPSi. Prints each library's count of exported symbols.

    python3 scripts/check-symbols.py build/release/src/libgipsi_*.so
"""
import re
import subprocess
import sys

# A symbol of Eigen's or nlohmann's own: after "typeinfo for " and the like, and a template
# function's return type, the name starts with their namespace.
PREFIX = re.compile(r"^(typeinfo name for |typeinfo for |vtable for |guard variable for )")
FOREIGN = re.compile(r"^([\w:]+ )?(Eigen|nlohmann)::")


def exported(library):
    out = subprocess.run(["nm", "-DC", "--defined-only", library], check=True,
                         capture_output=True, text=True).stdout
    return [line.split(" ", 2)[2] for line in out.splitlines() if line.count(" ") >= 2]


def main(libraries):
    if not libraries:
        sys.exit("usage: check-symbols.py LIBRARY...")
    failed = False
    for library in libraries:
        symbols = exported(library)
        ours = [s for s in symbols if "gipsi::" in s]
        leaked = [s for s in symbols if FOREIGN.match(PREFIX.sub("", s))]
        print(f"{library}: {len(symbols)} exported, {len(ours)} of them GiPSi's, "
              f"{len(leaked)} of Eigen or nlohmann")
        if not ours:
            print(f"  {library} exports nothing of GiPSi: is GIPSI_EXPORT missing?")
            failed = True
        for s in leaked[:10]:
            print(f"  leaked: {s[:160]}")
        failed |= bool(leaked)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main(sys.argv[1:])
