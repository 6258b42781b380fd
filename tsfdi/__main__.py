"""``python -m tsfdi``: the ``tsfdi`` command line (:func:`tsfdi.cli.main`)."""

from tsfdi.cli import main

raise SystemExit(main())
