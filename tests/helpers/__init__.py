"""Helpers shared by the tests of several packages.

The tests are laid out one way: ``tests/<package>/test_<module>.py`` for the code of
``src/armctl/<package>/<module>.py``, one ``test_validation.py`` per package for the errors bad input gets, the
helpers of one package's tests in ``tests/<package>/helpers.py``, the helpers shared across packages here, and
the pytest fixtures (only fixtures) in ``conftest.py`` files.
"""
