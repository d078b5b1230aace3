"""The mark of the tests that need the ordered factorisation (``solvers.ordered_ldl``): skipped
where qdldl's module does not export QDLDL and AMD, or is a release not checked."""
import pytest

from bd_uv.solvers import ordered_ldl

needs_ordered_ldl = pytest.mark.skipif(not ordered_ldl.available(),
                                       reason="qdldl's module does not export QDLDL and AMD here")
