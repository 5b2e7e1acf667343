import sys

try:
    from encoder_conformance.cli.main import console_main
except KeyboardInterrupt:  # Ctrl-C while Python is still importing: nothing was touched
    sys.exit(130)

console_main()
