import sys

from hdrjax.cli import main

sys.exit(main())
