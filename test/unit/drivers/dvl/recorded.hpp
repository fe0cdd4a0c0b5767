// Sentences as published by the vendors (Water Linked docs: dvl-protocol.md examples and the PD6
// example copied there from their encoder test), used verbatim.
#pragma once

namespace qnav_test {
inline constexpr const char* kWlWrz = "wrz,0.120,-0.400,2.000,y,1.30,1.855,1e-07;0;1.4;0;1.2;0;0.2;0;1e+09,7,14,123.00,1*50";
inline constexpr const char* kWlWru[] = {"wru,0,0.070,1.10,-40,-95*9c", "wru,1,-0.500,1.25,-62,-104*f0",
                                         "wru,2,2.200,1.40,-56,-98*18", "wru,3,1.800,1.35,-58,-96*a3"};
inline constexpr const char* kWlWrp[] = {"wrp,49056.809,0.41,0.15,1.23,0.4,53.9,13.0,19.3,0*de",
                                         "wrp,49057.269,0.39,0.18,1.23,0.4,53.9,13.0,19.3,0*e2",
                                         "wrp,49056.809,0.41,0.15,1.23,0.4,53.9,13.0,19.3,1*d9"};
inline constexpr const char* kWlWrx = "wrx,1164.94,0.000,0.000,0.000,2.707,-1.00,n,1*39";
inline constexpr const char* kPd6Ensemble =
    ":SA, +0.00, +0.00,  0.00\r\n"
    ":TS,22020812061800, 0.0, +0.0,   0.0,1475.0,  0\r\n"
    ":WI,    +0,    +0,    +0,    +0,V\r\n"
    ":WS,    +0,    +0,    +0,V\r\n"
    ":WE,    +0,    +0,    +0,V\r\n"
    ":WD,       +0.00,       +0.00,       +0.00,   0.00,  0.00\r\n"
    ":BI,  +123,  -420, +2000,    +0,A\r\n"
    ":BS,  -420,  +123, +2000,A\r\n"
    ":BE,    +0,    +0,    +0,V\r\n"
    ":BD,       +0.00,       +0.00,       +0.00,   5.32,  0.00\r\n";
}  // namespace qnav_test
