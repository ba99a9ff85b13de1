"""The OpenAPI check every HTTP suite relies on (strata_process.py): it passes the server's real
answers and flags what the description does not say, so a clean suite means something."""

import os
import unittest
import urllib.request

from strata_process import ServerProcess

SERVER = os.environ.get("STRATA_SERVER_BINARY", "build/server/strata-server")

PROBLEM = (b'{"type":"https://strata.dev/problems/not-found","title":"Not found","status":404,'
           b'"detail":"no route"}')


class OpenApiCheckTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.server = ServerProcess(SERVER, ["--demo"])
        cls.check = cls.server.openapi()

    @classmethod
    def tearDownClass(cls):
        cls.server.stop()

    def test_real_answers_pass_through_http_client_checked(self):
        self.assertIsNotNone(self.check)
        for path in ("/v1/scene", "/v1/stats", "/v1/scene/instances?limit=3", "/v1/plan",
                     "/v1/scene/tree?depth=2", "/livez"):
            with urllib.request.urlopen(self.server.url + path, timeout=30) as answer:
                body = answer.read()
            self.assertEqual(self.check.problems("GET", path, 200, "application/json", body), [])

    def test_an_undocumented_status_or_media_type_is_flagged(self):
        self.assertEqual(self.check.problems("GET", "/v1/scene", 418, "application/json", b"{}"),
                         ["status 418 is not documented"])
        found = self.check.problems("GET", "/v1/scene", 200, "text/html", b"<p>")
        self.assertIn("media type 'text/html' is not documented", found[0])

    def test_a_body_off_its_schema_is_flagged_with_where(self):
        found = self.check.problems("GET", "/v1/scene", 200, "application/json",
                                    b'{"version": -1}')
        self.assertTrue(any("counts" in f for f in found), found)
        self.assertTrue(any(f.startswith("/version:") for f in found), found)
        wrong_title = PROBLEM.replace(b'"Not found"', b'"Gone"')
        self.assertNotEqual(self.check.problems("GET", "/v1/scene/meshes/x", 404,
                                                "application/problem+json", wrong_title), [])

    def test_unknown_routes_and_methods_may_answer_problems_only(self):
        self.assertEqual(self.check.problems("GET", "/nope", 404, "application/problem+json",
                                             PROBLEM), [])
        self.assertNotEqual(self.check.problems("GET", "/nope", 200, "application/json", b"{}"),
                            [])
        self.assertEqual(self.check.problems("OPTIONS", "/v1/scene", 204, "", b""), [])

    def test_rest_parameters_and_shared_refusals_resolve(self):
        self.assertEqual(self.check.problems("GET", "/web/js/app.js", 404,
                                             "application/problem+json", PROBLEM.replace(
                                                 b'"no route"', b'"no file"')), [])
        timeout = (b'{"type":"https://strata.dev/problems/request-timeout","title":'
                   b'"Request timeout","status":408,"detail":"slow"}')
        self.assertEqual(self.check.problems("POST", "/v1/edits", 408,
                                             "application/problem+json", timeout), [])


if __name__ == "__main__":
    unittest.main()
