"""The payloads of test_attacks.py, their builders and the table of expected grades."""
