#!/usr/bin/env python3
"""ctest driver: starts uavsim-server on an ephemeral API port, runs docs/examples/api_client.py --check
against it, stops the server. Usage: run_python_example.py SERVER WORLD CLIENT"""

import re
import subprocess
import sys


def main():
    server_bin, world, client = sys.argv[1:4]
    server = subprocess.Popen(
        [server_bin, world, "--api-port", "0", "--mavlink-port", "-1", "--rate", "0"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        port = None
        for line in server.stdout:  # the server prints its API address once it listens
            sys.stdout.write(line)
            match = re.search(r"sim API on tcp:[0-9.]+:(\d+)", line)
            if match:
                port = match.group(1)
                break
        if port is None:
            print("the server did not print its API port")
            return 1
        return subprocess.run([sys.executable, client, "--port", port, "--check"], timeout=50).returncode
    finally:
        server.terminate()
        server.wait(timeout=10)


if __name__ == "__main__":
    sys.exit(main())
