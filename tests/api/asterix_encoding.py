"""An ASTERIX encoder for the tests, written from the EUROCONTROL specifications (not the service's
code): CAT048 target reports, CAT034 service messages, CAT021 ADS-B reports, and the UDP
payloads of a pcap file.

Each record is its FSPEC (FRN bits, FX chaining) then its items in FRN order; a data block is
CAT, LEN (2 bytes, big-endian, the whole block) and its records. Quantisation is the
specification's: the tests feed the JSON twin of a scene the values the encoding keeps.
"""

from __future__ import annotations

import struct
from collections.abc import Mapping

NM = 1852.0
FOOT = 0.3048
TOD_LSB = 1 / 128
RHO_LSB = 1 / 256  # NM
THETA_LSB = 360 / 2**16  # degrees
FL_LSB = 1 / 4  # flight levels
LATLON_LSB = 180 / 2**23  # degrees (I021/130)
GS_LSB = 2**-14  # NM/s
TA_LSB = 360 / 2**16
HEIGHT_LSB = 6.25  # ft


def fspec(frns: set[int]) -> bytes:
    """The FSPEC of a record holding the items ``frns`` (field reference numbers, from 1)."""
    octets = (max(frns) + 6) // 7
    out = bytearray(octets)
    for frn in frns:
        octet, bit = divmod(frn - 1, 7)
        out[octet] |= 0x80 >> bit
    for octet in range(octets - 1):
        out[octet] |= 0x01  # FX: another octet follows
    return bytes(out)


def record(items: Mapping[int, bytes]) -> bytes:
    """A record: its FSPEC and its items in FRN order."""
    return fspec(set(items)) + b"".join(items[frn] for frn in sorted(items))


def block(category: int, records: list[bytes]) -> bytes:
    body = b"".join(records)
    return bytes([category]) + (3 + len(body)).to_bytes(2, "big") + body


def _u(value: int, size: int) -> bytes:
    return value.to_bytes(size, "big", signed=False)


def _s(value: int, size: int) -> bytes:
    return value.to_bytes(size, "big", signed=True)


def quantised(value: float, lsb: float) -> int:
    return round(value / lsb)


def cat048(
    sac: int,
    sic: int,
    tod: float,
    rho_nm: float,
    theta_deg: float,
    flight_level: float | None = None,
    address: int | None = None,
    track_number: int | None = None,
) -> bytes:
    """A CAT048 target report: I010, I140, I020 (TYP 5: single Mode S roll-call), I040, and
    optionally I090, I220, I161."""
    items = {
        1: _u(sac, 1) + _u(sic, 1),
        2: _u(quantised(tod, TOD_LSB), 3),
        3: bytes([5 << 5]),
        4: _u(quantised(rho_nm, RHO_LSB), 2) + _u(quantised(theta_deg, THETA_LSB) % 2**16, 2),
    }
    if flight_level is not None:
        items[6] = _s(quantised(flight_level, FL_LSB), 2)  # V = G = 0: bits 16, 15 clear
    if address is not None:
        items[8] = _u(address, 3)
    if track_number is not None:
        items[11] = _u(track_number, 2)
    return record(items)


def cat034_north(sac: int, sic: int, tod: float, period: float) -> bytes:
    """A CAT034 north marker (message type 1) with the antenna rotation period (I034/041)."""
    return record(
        {
            1: _u(sac, 1) + _u(sic, 1),
            2: bytes([1]),
            3: _u(quantised(tod, TOD_LSB), 3),
            5: _u(quantised(period, TOD_LSB), 2),
        }
    )


def cat034_sector(sac: int, sic: int, tod: float, azimuth_deg: float) -> bytes:
    """A CAT034 sector crossing (message type 2)."""
    return record(
        {
            1: _u(sac, 1) + _u(sic, 1),
            2: bytes([2]),
            3: _u(quantised(tod, TOD_LSB), 3),
            4: _u(quantised(azimuth_deg, 360 / 2**8) % 256, 1),
        }
    )


def cat021(
    sac: int,
    sic: int,
    tod: float,
    lat: float,
    lon: float,
    address: int,
    ground_speed_nm_s: float,
    track_angle_deg: float,
    height_ft: float,
    nacp: int,
    nacv: int,
) -> bytes:
    """A CAT021 (v2.x) report: I010, I040, I071, I130, I080, I140, I090 (NACv, NACp), I160."""
    return record(
        {
            1: _u(sac, 1) + _u(sic, 1),
            2: bytes([0]),  # target report descriptor: 24-bit address, no extension
            5: _u(quantised(tod, TOD_LSB), 3),
            6: _s(quantised(lat, LATLON_LSB), 3) + _s(quantised(lon, LATLON_LSB), 3),
            11: _u(address, 3),
            16: _s(quantised(height_ft, HEIGHT_LSB), 2),
            17: bytes([(nacv << 5) | (8 << 1) | 1, (nacp << 1)]),  # NACv, NIC 8 | NACp
            26: _u(quantised(ground_speed_nm_s, GS_LSB), 2)
            + _u(quantised(track_angle_deg, TA_LSB) % 2**16, 2),
        }
    )


def udp_payloads(pcap: bytes) -> list[bytes]:
    """The UDP payloads of a pcap file of Ethernet frames (libpcap format, IPv4)."""
    magic = struct.unpack("<I", pcap[:4])[0]
    endian = "<" if magic in (0xA1B2C3D4, 0xA1B23C4D) else ">"
    position, payloads = 24, []
    while position + 16 <= len(pcap):
        captured = struct.unpack(endian + "I", pcap[position + 8 : position + 12])[0]
        frame = pcap[position + 16 : position + 16 + captured]
        position += 16 + captured
        ip = frame[14:]
        assert ip[9] == 17, "not UDP"
        udp = ip[(ip[0] & 0x0F) * 4 :]
        payloads.append(udp[8 : int.from_bytes(udp[4:6], "big")])  # UDP length: no padding
    return payloads
